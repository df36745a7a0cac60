//! Spatial tendons: moment arms against geometry (a string wrapped on a pulley pulls
//! with the pulley's radius) and against finite differences of the tendon's length, on
//! MuJoCo Menagerie's tendon-driven Aero hand. MuJoCo's own arms are checked in
//! tests/mjcf.rs (`menagerie-aero`).

use grasp_io::hand::HandFile;
use grasp_io::urdf::Robot;
use std::path::PathBuf;

/// A hinge about z at the origin, a geom `shape` of radius 0.02 centred on its axis and
/// turning with it, a site fixed at (−0.1, 0.03, 0) and one on the arm at (0.1, 0.03, 0)
/// (at q = 0), and a tendon from the fixed site around the geom (on the side of
/// `side`, when given) to the arm's site.
fn pulley(shape: &str, side: Option<[f64; 3]>) -> Robot {
    let side_site = side.map_or(String::new(), |p| {
        format!("<site name=\"side\" pos=\"{} {} {}\"/>", p[0], p[1], p[2])
    });
    let side_attr = if side.is_some() {
        " sidesite=\"side\""
    } else {
        ""
    };
    let text = format!(
        r#"<mujoco><compiler angle="radian"/><worldbody>
        <site name="a" pos="-0.1 0.03 0"/>{side_site}
        <body name="arm"><joint name="q" axis="0 0 1"/>
          <geom name="g" type="{shape}" size="0.02 0.05"/>
          <site name="b" pos="0.1 0.03 0"/>
        </body></worldbody>
        <tendon><spatial name="t"><site site="a"/><geom geom="g"{side_attr}/><site site="b"/></spatial></tendon>
        <actuator><motor name="m" tendon="t"/></actuator></mujoco>"#
    );
    Robot::parse_mjcf(&text, "pulley.xml", None).unwrap()
}

fn arm(robot: &Robot, q: f64) -> (f64, f64) {
    let (length, arms) = robot.tendon_moments(0, &robot.pose(&[q])).unwrap();
    assert_eq!(arms.len(), 1);
    (length, arms[0].1)
}

#[test]
fn a_string_wrapped_on_a_pulley_pulls_with_its_radius() {
    for shape in ["cylinder", "sphere"] {
        // Wrapped under the pulley: the arc grows by r dq as the arm turns.
        let robot = pulley(shape, Some([0.0, -0.05, 0.0]));
        for q in [-0.3, 0.0, 0.4] {
            let (_, m) = arm(&robot, q);
            assert!((m - 0.02).abs() <= 1e-15, "{shape} at q = {q}: {m}");
        }
        // Without the side site the straight string misses the pulley: the arm is the
        // derivative of |b − a| = u·(z × b), −0.03 at q = 0.
        let robot = pulley(shape, None);
        let (length, m) = arm(&robot, 0.0);
        assert!((length - 0.2).abs() <= 1e-16, "{length}");
        assert!((m + 0.03).abs() <= 1e-16, "{shape}: {m}");
    }
}

/// A string laid tangent to a pulley touches it at one point: its length is the
/// straight distance, not that plus a full turn (2π r), whichever way rounding tips
/// the order of the two tangent points. The ends are those of a string of the Aero
/// hand, as its kinematics place them (tangent to within rounding, the second end its
/// side site), where the order came out reversed.
#[test]
fn a_string_tangent_to_a_pulley_takes_no_turn() {
    let text = r#"<mujoco><compiler angle="radian"/><worldbody>
        <site name="a" pos="0.015000000000000005 0.0024999999999999953 0"/>
        <body name="arm"><joint name="q" axis="0 0 1"/>
          <geom name="g" type="cylinder" size="0.0025 0.005"/>
          <site name="b" pos="-0.0020000000000000065 0.002500000000000001 0"/>
        </body></worldbody>
        <tendon><spatial name="t"><site site="a"/><geom geom="g" sidesite="b"/><site site="b"/></spatial></tendon>
        <actuator><motor name="m" tendon="t"/></actuator></mujoco>"#;
    let robot = Robot::parse_mjcf(text, "tangent.xml", None).unwrap();
    let (length, _) = arm(&robot, 0.0);
    // Within the string's rounding: a few ε inside the circle, it wraps by an angle of
    // order √ε, a detour of order r √ε.
    assert!((length - 0.017).abs() <= 0.0025 * 1e-7, "{length}");
}

/// Sites that coincide at the origin (a string of no length, where the scale its
/// lengths are judged against is 0 too): length 0 and a zero arm, not NaN.
#[test]
fn a_string_of_no_length_at_the_origin_pulls_nothing() {
    let text = r#"<mujoco><worldbody><site name="a" pos="0 0 0"/>
        <body name="arm"><joint name="q" axis="0 0 1"/><site name="b" pos="0 0 0"/>
        <geom name="g" type="sphere" size="0.01" pos="0.1 0 0"/></body></worldbody>
        <tendon><spatial name="t"><site site="a"/><site site="b"/></spatial></tendon>
        <actuator><motor name="m" tendon="t"/></actuator></mujoco>"#;
    let robot = Robot::parse_mjcf(text, "origin.xml", None).unwrap();
    assert_eq!(arm(&robot, 0.0), (0.0, 0.0));
}

#[test]
fn moment_arms_are_the_derivative_of_the_length() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/mjcf/menagerie/aero_right.xml");
    let robot = Robot::load(&path).unwrap();
    assert_eq!(robot.tendons.len(), 20);
    let n = robot.independent.len();
    // A fixed walk through the joint ranges (within [0, 0.95], inside every range).
    let mut state = 12345u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let h = 1e-6;
    let (mut worst, mut checked, mut kinks): (f64, usize, usize) = (0.0, 0, 0);
    for _ in 0..40 {
        let q: Vec<f64> = (0..n).map(|_| 0.05 + 0.9 * next()).collect();
        let pose = robot.pose(&q);
        for t in 0..robot.tendons.len() {
            let (_, arms) = robot.tendon_moments(t, &pose).unwrap();
            for k in 0..n {
                // ∂L/∂q_k through the couplings: the joints that follow q_k.
                let analytic: f64 = arms
                    .iter()
                    .filter_map(|&(j, m)| {
                        let c = robot.coupling[j]?;
                        (c.independent == k).then_some(c.multiplier * m)
                    })
                    .sum();
                let length_at = |dq: f64| {
                    let mut x = q.clone();
                    x[k] += dq;
                    robot.tendon_moments(t, &robot.pose(&x)).unwrap().0
                };
                let (l0, lp, lm) = (length_at(0.0), length_at(h), length_at(-h));
                // Where the string just grazes a geom, MuJoCo's wrap (and so this
                // one) switches between arcs θ and 2π − θ or between wrapped and
                // straight: the length jumps, and has no derivative there.
                if ((lp - l0) - (l0 - lm)).abs() > 1e-9 {
                    kinks += 1;
                    continue;
                }
                checked += 1;
                let fd = (lp - lm) / (2.0 * h);
                // Central differences: O(h²) truncation and O(ε L / h) rounding, with
                // L ≈ 0.1 m and arms up to about 0.01 m.
                let err = (fd - analytic).abs();
                worst = worst.max(err);
                assert!(
                    err <= 1e-8,
                    "{} on joint {k}: {analytic} vs {fd}",
                    robot.tendons[t].name
                );
            }
        }
    }
    assert!(kinks * 100 <= checked, "{kinks} kinks in {checked}");
    eprintln!("Aero hand, 20 tendons, 40 configurations: worst |∂L/∂q − central difference| {worst:.1e} m over {checked} arms ({kinks} at a kink)");
}

#[test]
fn a_spatial_tendon_no_actuator_uses_may_be_malformed() {
    // Only a tendon that an actuator pulls on or a spring stretches must be usable: a
    // bare string wrapped on a box is ignored, a spring on it is a named error.
    let text = |attrs: &str| {
        format!(
            r#"<mujoco><worldbody><site name="s0"/><body><joint name="a"/>
        <geom name="box" type="box" size="1 1 1"/><site name="s1" pos="1 0 0"/></body></worldbody>
        <tendon><spatial name="string"{attrs}><site site="s0"/><geom geom="box"/><site site="s1"/></spatial></tendon>
        <actuator><motor joint="a"/></actuator></mujoco>"#
        )
    };
    let robot = Robot::parse_mjcf(&text(""), "string.xml", None).unwrap();
    assert!(robot.tendons.is_empty() && robot.springs.is_empty());
    let err = Robot::parse_mjcf(&text(r#" stiffness="10""#), "spring.xml", None).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("<spatial> (line 3): has a spring (stiffness), but cannot be used")
            && msg.contains("a tendon wraps spheres and cylinders only"),
        "{msg}"
    );
}

#[test]
fn a_side_site_inside_its_geom_is_a_named_error() {
    // The side site turns with the arm into the cylinder: MuJoCo would wrap the string
    // inside, which is not modelled.
    let text = r#"<mujoco><compiler angle="radian"/><worldbody><site name="a" pos="-0.1 0.03 0"/>
        <body name="arm"><joint name="q" axis="0 0 1"/>
          <geom name="g" type="cylinder" size="0.02 0.05"/>
          <site name="side" pos="0.01 0 0"/><site name="b" pos="0.1 0.03 0"/>
        </body></worldbody>
        <tendon><spatial name="t"><site site="a"/><geom geom="g" sidesite="side"/><site site="b"/></spatial></tendon>
        <actuator><motor name="m" tendon="t"/></actuator></mujoco>"#;
    let robot = Robot::parse_mjcf(text, "inside.xml", None).unwrap();
    let file: HandFile = serde_json::from_value(serde_json::json!({
        "hand": {"model": "inside.xml", "joint_positions": {"q": 0.1}},
        "contacts": [{"link": "arm", "position": [0.1, 0, 0], "normal": [0, -1, 0], "model": "fpc"}],
        "wrench": [0, 1, 0, 0, 0, 0]
    }))
    .unwrap();
    // The hand loads; the configuration is what fails.
    assert!(file.grasps(&robot).is_ok());
    let e = file.build(&robot).unwrap_err().to_string();
    assert!(
        e.contains("joint_positions") && e.contains("side site of geom `g`"),
        "{e}"
    );
}
