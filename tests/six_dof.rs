//! Bodies in six degrees of freedom (issue 22), through the Coupling API: a 3D body held at any
//! orientation turns on at its world angular velocity; loads in body axes are the world loads
//! turned; orientations and angular velocities a body cannot take are errors that change
//! nothing; a frame turning about an oblique axis gives the centrifugal and Coriolis terms.

use crate::common;
use sphfmu::boundary::frame::FrameConfig;
use sphfmu::boundary::kinematics::Motion;
use sphfmu::case::Case;
use sphfmu::coupling::{orientation, BodyKinematics, Coupling, CouplingOptions};

fn options() -> CouplingOptions {
    CouplingOptions {
        threads: 2,
        resolution: 0.5,
        ..CouplingOptions::default()
    }
}

fn box3d() -> Coupling {
    let case = Case::parse(&common::model_text("box3d.toml")).unwrap();
    Coupling::new(&case, &options()).unwrap()
}

#[test]
fn a_held_body_turns_on_at_its_world_angular_velocity() {
    let mut c = box3d();
    let b = c.body_index("box").unwrap();
    let q0 = nalgebra::UnitQuaternion::from_euler_angles(0.02, -0.03, 0.01);
    let w = [0.2, -0.1, 0.3];
    let k = BodyKinematics {
        orientation: orientation::to_array(&q0),
        angular_velocity: w,
        ..Default::default()
    };
    c.set_body_kinematics(b, &k).unwrap();
    c.step_to(0.05).unwrap();
    let now = c.body_kinematics(b);
    let expected =
        nalgebra::UnitQuaternion::from_scaled_axis(nalgebra::Vector3::from(w) * 0.05) * q0;
    let got = orientation::to_unit(&now.orientation);
    assert!(got.angle_to(&expected) < 1e-14, "{got} {expected}");
    assert_eq!(now.angular_velocity, w);
    // loads in body axes: Rᵀ F and Rᵀ T to round-off
    let loads = c.loads()[b];
    let (f, t) = (
        nalgebra::Vector3::from(loads.force),
        nalgebra::Vector3::from(loads.torque),
    );
    let fb = got.inverse_transform_vector(&f);
    let tb = got.inverse_transform_vector(&t);
    let scale = f.norm().max(t.norm());
    assert!(scale > 1.0, "the water rests on the box: {f}");
    let err = (fb - nalgebra::Vector3::from(loads.force_body))
        .abs()
        .max()
        .max(
            (tb - nalgebra::Vector3::from(loads.torque_body))
                .abs()
                .max(),
        );
    assert!(err < 1e-15 * scale, "{err:e}");
}

#[test]
fn orientations_a_body_cannot_take_are_errors_that_change_nothing() {
    let mut c = box3d();
    let b = c.body_index("box").unwrap();
    c.step_to(0.01).unwrap();
    let saved = c.save().unwrap();
    let with = |orientation: [f64; 4], angular_velocity: [f64; 3]| BodyKinematics {
        orientation,
        angular_velocity,
        ..Default::default()
    };
    let bad = [
        (
            with([1.0 + 2e-6, 0.0, 0.0, 0.0], [0.0; 3]),
            "body \"box\" orientation: a unit quaternion",
        ),
        (
            with([0.0; 4], [0.0; 3]),
            "body \"box\" orientation: a unit quaternion",
        ),
        (
            with([f64::NAN, 0.0, 0.0, 1.0], [0.0; 3]),
            "body \"box\" orientation: entries must be finite",
        ),
        (
            with(orientation::IDENTITY, [0.0, f64::INFINITY, 0.0]),
            "body \"box\" angular_velocity: entries must be finite",
        ),
    ];
    for (k, want) in bad {
        let e = c.set_body_kinematics(b, &k).unwrap_err().0;
        assert!(e.starts_with(want), "{e:?} should start with {want:?}");
    }
    assert_eq!(
        c.save().unwrap(),
        saved,
        "a refused input changed the state"
    );
    // within 1e-6 of unit length: renormalised
    c.set_body_kinematics(b, &with([1.0 + 5e-7, 0.0, 0.0, 0.0], [0.0; 3]))
        .unwrap();
    assert_eq!(c.body_kinematics(b).orientation, orientation::IDENTITY);

    // a 2D body turns about z only
    let case = Case::parse(&common::model_text("free-piston2d.toml")).unwrap();
    let full = CouplingOptions {
        threads: 2,
        ..CouplingOptions::default()
    };
    let mut c = Coupling::new(&case, &full).unwrap();
    let piston = c.body_index("piston").unwrap();
    c.step_to(0.01).unwrap();
    let saved = c.save().unwrap();
    let tilted = orientation::to_array(&nalgebra::UnitQuaternion::from_euler_angles(0.1, 0.0, 0.0));
    for k in [
        BodyKinematics {
            position: [1.0, 0.1, 0.0],
            angular_velocity: [0.5, 0.0, 1.0],
            ..Default::default()
        },
        BodyKinematics {
            position: [1.0, 0.1, 0.0],
            orientation: tilted,
            ..Default::default()
        },
    ] {
        let e = c.set_body_kinematics(piston, &k).unwrap_err().0;
        assert!(e.contains("turns about z only in a 2D case"), "{e}");
    }
    assert_eq!(
        c.save().unwrap(),
        saved,
        "a refused input changed the state"
    );
    let mut k = BodyKinematics {
        position: [1.0, 0.1, 0.0],
        ..Default::default()
    };
    k.set_planar(0.0, 0.0);
    c.set_body_kinematics(piston, &k).unwrap();
}

#[test]
fn a_frame_turning_about_an_oblique_axis_gives_the_fictitious_forces() {
    // a 3D frame at constant rate about an oblique axis: at rest in the frame, a particle
    // feels −Ω × (Ω × r); moving at v, also −2 Ω × v (Ω in frame axes = the world Ω, since
    // the frame turns about Ω)
    let axis = [1.0, 2.0, -0.5];
    let frame = FrameConfig {
        motion: Motion::Ramp {
            velocity: vec![0.0; 3],
            angular_velocity: 1.5,
            ramp_time: 0.0,
            start: 0.0,
        },
        reference: Some(vec![0.1, 0.0, 0.0]),
        axis: Some(axis.to_vec()),
        orientation: Default::default(),
    };
    frame.validate(3).unwrap();
    let mut f = frame.build::<3>();
    f.place(0.7);
    let n = nalgebra::Vector3::from(axis).normalize();
    let omega = n * 1.5;
    let x = nalgebra::Vector3::new(0.3, -0.2, 0.4);
    let v = nalgebra::Vector3::new(0.5, 0.1, -0.2);
    let r = x - nalgebra::Vector3::new(0.1, 0.0, 0.0);
    let got = f.body_force(&nalgebra::Vector3::zeros(), &x, &v);
    let want = -omega.cross(&omega.cross(&r)) - 2.0 * omega.cross(&v);
    assert!((got - want).norm() < 1e-14, "{got} {want}");
    // gravity seen from the turned frame: Rᵀ g
    let g = nalgebra::Vector3::new(0.0, 0.0, -9.81);
    let turned =
        nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(n), 1.5 * 0.7);
    assert!((f.uniform(&g) - turned.inverse_transform_vector(&g)).norm() < 1e-14);
}

#[test]
fn a_frame_driven_from_outside_pushes_the_water_like_a_moved_tank() {
    // the closed tank of closed-tank2d.toml, computed in its own frame, which a master
    // accelerates at A = 2 m/s² along x: the water (516.3 kg/m) feels −A, and the tank holds
    // it with M A, so the water pushes the tank with −M A
    let text = common::model_text("closed-tank2d.toml")
        + "\n[frame]\nmotion = { type = \"external\" }\nreference = [0.5, 0.25]\n";
    let case = Case::parse(&text).unwrap();
    let full = CouplingOptions {
        threads: 2,
        ..CouplingOptions::default()
    };
    let mut c = Coupling::new(&case, &full).unwrap();
    assert!(c.has_external_frame());
    let tank = c.body_index("tank").unwrap();
    let mass = c.diagnostics().mass;
    c.step_to(0.05).unwrap();
    let at_rest = c.loads()[tank].force;
    let push = BodyKinematics {
        acceleration: [2.0, 0.0, 0.0],
        ..Default::default()
    };
    c.set_frame_kinematics(&push).unwrap();
    let (mut sum, mut n) = (0.0, 0);
    for k in 1..=50 {
        c.step_to(0.05 + 0.01 * k as f64).unwrap();
        if k > 10 {
            sum += c.loads()[tank].force[0];
            n += 1;
        }
    }
    let fx = sum / n as f64;
    // measured over t = 0.15 … 0.55 s (five acoustic periods 2L/c): −1044.0 N/m against
    // −1032.6 (+1.1 %; the weight at rest reads +1.5 %)
    assert!(
        (fx / (-mass * 2.0) - 1.0).abs() < 0.03,
        "mean F_x {fx} against −M A = {} (at rest {at_rest:?})",
        -mass * 2.0
    );
    let k = c.frame_kinematics().unwrap();
    assert_eq!(k.acceleration, [2.0, 0.0, 0.0]);
    // the frame's motion is checked as a body's, and saved with the state
    let saved = c.save().unwrap();
    let tilted = orientation::to_array(&nalgebra::UnitQuaternion::from_euler_angles(0.1, 0.0, 0.0));
    let bad = BodyKinematics {
        orientation: tilted,
        ..Default::default()
    };
    let e = c.set_frame_kinematics(&bad).unwrap_err().0;
    assert!(e.starts_with("frame orientation"), "{e}");
    c.restore(&saved).unwrap();
    assert_eq!(c.frame_kinematics().unwrap().acceleration, [2.0, 0.0, 0.0]);
    // a case without an external frame refuses frame inputs
    let plain = Case::parse(&common::model_text("closed-tank2d.toml")).unwrap();
    let mut c = Coupling::new(&plain, &full).unwrap();
    let e = c.set_frame_kinematics(&push).unwrap_err().0;
    assert!(e.contains("no [frame] with motion"), "{e}");
}
