//! What the URDF and MJCF oracle tests share.

use grasp_io::urdf::Robot;

/// The largest difference between the oracle's frames of one configuration (`case`,
/// its `frames`: position, then the rotation matrix row by row, per link or site) and
/// where the robot puts them; 0 for a case without frames. Fails above 1e-12.
pub(crate) fn frame_error(robot: &Robot, case: &serde_json::Value, model: &str) -> f64 {
    let Some(frames) = case["frames"].as_object() else {
        return 0.0;
    };
    let mut q = vec![0.0; robot.independent.len()];
    for (name, v) in case["problem"]["hand"]["joint_positions"]
        .as_object()
        .unwrap()
    {
        let j = robot.joint(name).unwrap();
        q[robot.coupling[j].unwrap().independent] = v.as_f64().unwrap();
    }
    let pose = robot.pose(&q);
    let mut worst = 0.0f64;
    for (name, want) in frames {
        let want: Vec<f64> = serde_json::from_value(want.clone()).unwrap();
        let (link, offset) = robot.named_frame(name, "frames").unwrap();
        let x = pose.links[link] * offset;
        let r = x.rotation.to_rotation_matrix();
        let got = (0..3)
            .map(|i| x.translation[i])
            .chain((0..9).map(|e| r[e / 3][e % 3]));
        let err = got
            .zip(&want)
            .fold(0.0f64, |a, (g, w)| a.max((g - w).abs()));
        assert!(err <= 1e-12, "{name}'s frame off by {err:e} in {model}");
        worst = worst.max(err);
    }
    worst
}
