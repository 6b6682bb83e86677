//! Output files: VTU snapshots (ParaView), CSV snapshots, the diagnostics time series, PNG plots.

pub mod plot;

use crate::particles::Particles;
use crate::sim::Diagnostics;
use std::fmt::Write as _;
use std::io::{self, Write};
use std::path::Path;

/// Append `row(i, out)` for i in 0..n to `s`, in order, the rows formatted in parallel
/// chunks: formatting floats was most of a snapshot's cost (0.14 s per snapshot of the
/// 148,632-particle 3D Sod on one thread), and a run's wall clock includes its snapshots.
/// The bytes do not depend on the chunking.
fn push_rows(s: &mut String, n: usize, row: impl Fn(usize, &mut String) + Sync) {
    use rayon::prelude::*;
    const CHUNK: usize = 4096;
    let parts: Vec<String> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut out = String::new();
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                row(i, &mut out);
            }
            out
        })
        .collect();
    for part in parts {
        s.push_str(&part);
    }
}

/// A particle vector's three components (zeros past D).
fn xyz<const D: usize>(x: &crate::particles::Vector<D>) -> [f64; 3] {
    std::array::from_fn(|k| if k < D { x[k] } else { 0.0 })
}

fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(tmp, path)
}

/// Snapshot as a VTU unstructured grid: one vertex cell per particle, fields as point data
/// (ASCII, so any ParaView or meshio opens it without a reader plug-in).
pub fn write_vtu<const D: usize>(path: &Path, p: &Particles<D>, time: f64) -> io::Result<()> {
    let n = p.len();
    let mut s = String::with_capacity(n * 200);
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n");
    let _ = writeln!(s, "<FieldData><DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">{time:e}</DataArray></FieldData>");
    let _ = writeln!(s, "<Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">");
    s.push_str("<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    push_rows(&mut s, n, |i, s| {
        let c = xyz(&p.pos[i]);
        let _ = writeln!(s, "{:e} {:e} {:e}", c[0], c[1], c[2]);
    });
    s.push_str("</DataArray></Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for i in 0..n {
        let _ = write!(s, "{i} ");
    }
    s.push_str("\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for i in 0..n {
        let _ = write!(s, "{} ", i + 1);
    }
    s.push_str("\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for _ in 0..n {
        s.push_str("1 ");
    }
    s.push_str("\n</DataArray>\n</Cells>\n<PointData Scalars=\"density\" Vectors=\"velocity\">\n");
    s.push_str("<DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    push_rows(&mut s, n, |i, s| {
        let c = xyz(&p.vel[i]);
        let _ = writeln!(s, "{:e} {:e} {:e}", c[0], c[1], c[2]);
    });
    s.push_str("</DataArray>\n");
    let scalars: [(&str, &Vec<f64>); 6] = [
        ("density", &p.rho),
        ("pressure", &p.pressure),
        ("internal_energy", &p.u),
        ("smoothing_length", &p.h),
        ("mass", &p.mass),
        ("sound_speed", &p.sound_speed),
    ];
    for (name, data) in scalars {
        let _ = writeln!(
            s,
            "<DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
        );
        push_rows(&mut s, n, |i, s| {
            let _ = write!(s, "{:e} ", data[i]);
        });
        s.push_str("\n</DataArray>\n");
    }
    s.push_str("<DataArray type=\"UInt32\" Name=\"id\" format=\"ascii\">\n");
    for v in &p.id {
        let _ = write!(s, "{v} ");
    }
    s.push_str("\n</DataArray>\n");
    // material; body (b + 1 for a wall particle of body b, else 0); port (k + 1 for a buffer
    // particle of port k, else 0)
    for (name, data) in [
        ("material", &p.material),
        ("body", &p.body),
        ("port", &p.port),
    ] {
        let _ = writeln!(
            s,
            "<DataArray type=\"UInt16\" Name=\"{name}\" format=\"ascii\">"
        );
        for v in data.iter() {
            let _ = write!(s, "{v} ");
        }
        s.push_str("\n</DataArray>\n");
    }
    s.push_str("</PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    write_atomic(path, s.as_bytes())
}

/// The point arrays of [`write_vtu`] (name, VTK type, components), for the `.pvtu` header of
/// a snapshot written in pieces; a unit test checks that every one of them is in a VTU.
pub const VTU_ARRAYS: [(&str, &str, usize); 11] = [
    ("velocity", "Float64", 3),
    ("density", "Float64", 1),
    ("pressure", "Float64", 1),
    ("internal_energy", "Float64", 1),
    ("smoothing_length", "Float64", 1),
    ("mass", "Float64", 1),
    ("sound_speed", "Float64", 1),
    ("id", "UInt32", 1),
    ("material", "UInt16", 1),
    ("body", "UInt16", 1),
    ("port", "UInt16", 1),
];

/// A snapshot written in pieces, one VTU per rank (`pieces`: file names relative to it), as
/// one ParaView dataset (`.pvtu`).
pub fn write_pvtu(path: &Path, pieces: &[String], time: f64) -> io::Result<()> {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PUnstructuredGrid GhostLevel=\"0\">\n",
    );
    let _ = writeln!(s, "<FieldData><DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">{time:e}</DataArray></FieldData>");
    s.push_str("<PPoints><PDataArray type=\"Float64\" NumberOfComponents=\"3\"/></PPoints>\n");
    s.push_str("<PPointData Scalars=\"density\" Vectors=\"velocity\">\n");
    for (name, kind, n) in VTU_ARRAYS {
        let _ = writeln!(
            s,
            "<PDataArray type=\"{kind}\" Name=\"{name}\" NumberOfComponents=\"{n}\"/>"
        );
    }
    s.push_str("</PPointData>\n");
    for piece in pieces {
        let _ = writeln!(s, "<Piece Source=\"{piece}\"/>");
    }
    s.push_str("</PUnstructuredGrid>\n</VTKFile>\n");
    write_atomic(path, s.as_bytes())
}

/// A ParaView collection (`.pvd`): the VTU files (names relative to it) at their times, so
/// they open as one time series.
pub fn write_pvd(path: &Path, entries: &[(f64, String)]) -> io::Result<()> {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
    );
    for (t, name) in entries {
        s.push_str(&format!(
            "<DataSet timestep=\"{t:e}\" part=\"0\" file=\"{name}\"/>\n"
        ));
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    std::fs::write(path, s)
}

/// Snapshot as CSV with columns x,y,z,vx,vy,vz,m,h,rho,u,P,cs,id,material (sarracen/pandas names).
pub fn write_csv<const D: usize>(path: &Path, p: &Particles<D>) -> io::Result<()> {
    let mut s = String::with_capacity(p.len() * 160);
    s.push_str(&csv_header(D));
    push_rows(&mut s, p.len(), |i, s| {
        let (x, v) = (xyz(&p.pos[i]), xyz(&p.vel[i]));
        let _ = writeln!(
            s,
            "{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{},{}",
            x[0],
            x[1],
            x[2],
            v[0],
            v[1],
            v[2],
            p.mass[i],
            p.h[i],
            p.rho[i],
            p.u[i],
            p.pressure[i],
            p.sound_speed[i],
            p.id[i],
            p.material[i]
        );
    });
    write_atomic(path, s.as_bytes())
}

/// The snapshot CSV's header: `name [unit]` per column (crate::units: a 2D particle's mass
/// is per metre of depth).
pub fn csv_header(dimension: usize) -> String {
    let m = crate::units::units(dimension).mass;
    format!(
        "x [m],y [m],z [m],vx [m/s],vy [m/s],vz [m/s],m [{m}],h [m],rho [kg/m3],u [J/kg],P [Pa],cs [m/s],id,material\n"
    )
}

/// Diagnostics time series, one CSV row per record, flushed as it goes so an aborted run
/// keeps everything written so far.
pub struct DiagnosticsWriter {
    file: io::BufWriter<std::fs::File>,
}

impl DiagnosticsWriter {
    /// The header in `dimension` (units per metre of depth in 2D, crate::units). `potential`
    /// is the energy in uniform gravity, −Σ m g·x; `total` = kinetic + internal + potential.
    pub fn header(dimension: usize) -> String {
        let u = crate::units::units(dimension);
        let (m, p, l, e) = (u.mass, u.momentum, u.angular_momentum, u.energy);
        format!(
            "time [s],step,dt [s],particles,mass [{m}],px [{p}],py [{p}],pz [{p}],Lx [{l}],Ly [{l}],Lz [{l}],kinetic [{e}],internal [{e}],potential [{e}],total [{e}]"
        )
    }

    pub fn create(path: &Path, dimension: usize) -> io::Result<Self> {
        let mut file = io::BufWriter::new(std::fs::File::create(path)?);
        writeln!(file, "{}", Self::header(dimension))?;
        Ok(Self { file })
    }

    pub fn record(&mut self, d: &Diagnostics) -> io::Result<()> {
        writeln!(
            self.file,
            "{:.17e},{},{:.17e},{},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e}",
            d.time, d.step, d.dt, d.particles, d.mass, d.momentum[0], d.momentum[1], d.momentum[2],
            d.angular_momentum[0], d.angular_momentum[1], d.angular_momentum[2],
            d.kinetic_energy, d.internal_energy, d.potential_energy, d.total_energy
        )?;
        self.file.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::Vector;

    /// The `.pvtu` header lists exactly the arrays a piece holds, with their types.
    #[test]
    fn pvtu_arrays_are_the_vtu_arrays() {
        let dir = tempfile::tempdir().expect("temp dir");
        let mut p = Particles::<2>::default();
        p.push(1.0, Vector::zeros(), Vector::zeros(), 1.0, 1.0, 0.1, 0);
        let path = dir.path().join("a.vtu");
        write_vtu(&path, &p, 0.0).expect("vtu");
        let text = std::fs::read_to_string(&path).expect("read");
        let arrays = text.matches("<DataArray").count();
        // TIME, the points and the three cell arrays besides the point data
        assert_eq!(
            arrays,
            VTU_ARRAYS.len() + 5,
            "a VTU array missing from VTU_ARRAYS"
        );
        for (name, kind, n) in VTU_ARRAYS {
            let tag = format!("type=\"{kind}\" Name=\"{name}\"");
            assert!(text.contains(&tag), "{tag} not in the VTU");
            assert_eq!(
                n == 3,
                text.contains(&format!("{tag} NumberOfComponents=\"3\"")),
                "{name}"
            );
        }
    }
}
