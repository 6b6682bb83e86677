//! Kernel quality on a perfect periodic 2D hexagonal lattice (Rosswog (2015) Sec. 3.1–3.2):
//! the indicators Q1–Q4 and the errors of the summation density and of the standard SPH
//! gradient of f = x, averaged over particles.

use crate::kernel::{AnyKernel, DimKernel, Kernel};
use serde::Serialize;

/// Mean absolute deviations over the lattice.
#[derive(Debug, Clone, Serialize)]
pub struct LatticeQuality {
    pub kernel: String,
    pub eta: f64,
    pub neighbours: f64,
    /// |Σ V W − 1|; with equal masses this is also the summation-density error |ρ/ρ0 − 1|
    pub q1: f64,
    /// |Σ V (r_b − r) W| / r_s
    pub q2: f64,
    /// |Σ V ∇W| · r_s
    pub q3: f64,
    /// mean over the four entries of |Σ V (r_b − r)^i ∇^j W − δ^ij|
    pub q4: f64,
    /// |(∂f/∂x)_SPH − 1| for f = x with the standard gradient Σ V f_b ∇W (f made periodic by
    /// taking the minimum-image offset, so f_b − f_a = Δx exactly)
    pub gradient_error: f64,
}

/// Points of an nx × ny periodic hexagonal lattice with sphere radius r_s (spacing 2 r_s).
pub fn hex_lattice(nx: usize, ny: usize, rs: f64) -> (Vec<[f64; 2]>, [f64; 2]) {
    let dy = 3f64.sqrt() * rs;
    let mut pts = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let x = (i as f64 + if j % 2 == 1 { 0.5 } else { 0.0 }) * 2.0 * rs;
            pts.push([x, j as f64 * dy]);
        }
    }
    (pts, [nx as f64 * 2.0 * rs, ny as f64 * dy])
}

/// Evaluate the indicators for `kernel` at `eta` on a 40 × 46 lattice (sampled at 100 points).
pub fn hex_quality(kernel: AnyKernel, eta: f64) -> LatticeQuality {
    let rs = 0.01;
    let (pts, period) = hex_lattice(40, 46, rs);
    let v0 = 2.0 * 3f64.sqrt() * rs * rs;
    let dk = DimKernel::<2>::new(kernel);
    let h = eta * v0.sqrt();
    let sample = 100;
    let mut acc = [0.0; 5];
    let mut nb = 0usize;
    for a in pts.iter().step_by(pts.len() / sample).take(sample) {
        let (mut s1, mut s2, mut s3, mut s4, mut gx) =
            (0.0, [0.0; 2], [0.0; 2], [[0.0; 2]; 2], 0.0);
        for b in &pts {
            let mut d = [b[0] - a[0], b[1] - a[1]];
            for k in 0..2 {
                d[k] -= period[k] * (d[k] / period[k]).round();
            }
            let r = d[0].hypot(d[1]);
            let e = dk.eval(r, h);
            if e.w > 0.0 && r > 0.0 {
                nb += 1;
            }
            // ∇_r W(|r − r_b|) at r = r_a: −dW/dr · d/r (d = r_b − r_a)
            let g = if r > 0.0 {
                [-e.dwdr * d[0] / r, -e.dwdr * d[1] / r]
            } else {
                [0.0; 2]
            };
            s1 += v0 * e.w;
            for i in 0..2 {
                s2[i] += v0 * d[i] * e.w;
                s3[i] += v0 * g[i];
                for j in 0..2 {
                    s4[i][j] += v0 * d[i] * g[j];
                }
            }
            // standard gradient Σ V_b f_b ∇_a W_ab, f_b = x_a + Δx: the x_a part is x_a·Q3
            gx += v0 * (a[0] + d[0]) * g[0];
        }
        acc[0] += (s1 - 1.0).abs();
        acc[1] += s2[0].hypot(s2[1]) / rs;
        acc[2] += s3[0].hypot(s3[1]) * rs;
        acc[3] +=
            ((s4[0][0] - 1.0).abs() + (s4[1][1] - 1.0).abs() + s4[0][1].abs() + s4[1][0].abs())
                / 4.0;
        acc[4] += (gx - 1.0).abs();
    }
    let n = sample as f64;
    LatticeQuality {
        kernel: kernel.name(),
        eta,
        neighbours: nb as f64 / n,
        q1: acc[0] / n,
        q2: acc[1] / n,
        q3: acc[2] / n,
        q4: acc[3] / n,
        gradient_error: acc[4] / n,
    }
}

/// The η grid of an `--eta-scan FROM:TO:STEP` argument, checked: 0 < FROM ≤ TO ≤ 4 and
/// 0 < STEP, at most 1000 points. At η = 4 the support 2h is 0.15, within half the 0.8-wide
/// periodic test lattice, so the nearest-image sums of [`hex_quality`] see each neighbour once.
pub fn eta_grid(spec: &str) -> Result<Vec<f64>, String> {
    let parts: Vec<&str> = spec.split(':').collect();
    let [from, to, step] = parts[..] else {
        return Err(format!("--eta-scan: expected FROM:TO:STEP, got '{spec}'"));
    };
    let num = |name: &str, s: &str| {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("--eta-scan: {name} '{s}' is not a number"))
    };
    let (from, to, step) = (num("FROM", from)?, num("TO", to)?, num("STEP", step)?);
    if !(from > 0.0 && from <= to && to <= 4.0) {
        return Err(format!(
            "--eta-scan: need 0 < FROM <= TO <= 4, got FROM {from}, TO {to}"
        ));
    }
    if step <= 0.0 {
        return Err(format!("--eta-scan: STEP must be > 0, got {step}"));
    }
    // the count from a rounded quotient, so that 1.0:3.0:0.02 ends at 3.0 exactly
    let n = ((to - from) / step + 1e-9).floor() as usize + 1;
    if n > 1000 {
        return Err(format!(
            "--eta-scan: {n} points, at most 1000 allowed (raise STEP)"
        ));
    }
    Ok((0..n).map(|i| from + i as f64 * step).collect())
}

/// Markdown table of Q1 = ε_ρ (the mean |Σ_b V_b W_ab − 1| of [`hex_quality`]) for every kernel
/// at every η of `etas`: the curves of Rosswog (2015) Fig. 4, one row per η.
pub fn eta_scan_table(etas: &[f64]) -> String {
    let kernels = AnyKernel::all();
    let mut o = String::from("| η |");
    for k in &kernels {
        o.push_str(&format!(" {} |", k.name()));
    }
    o.push_str(&format!("\n|---|{}\n", "---|".repeat(kernels.len())));
    for &eta in etas {
        o.push_str(&format!("| {eta:.4} |"));
        for &k in &kernels {
            o.push_str(&format!(" {:.3e} |", hex_quality(k, eta).q1));
        }
        o.push('\n');
    }
    o
}
