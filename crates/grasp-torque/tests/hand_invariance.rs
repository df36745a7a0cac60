//! Hand files give the same grasp in any units and any object frame.
//!
//! Units: every length of a bundled hand is rescaled
//! in its URDF or MJCF text (joint and body origins, geom and site sizes, the wrap
//! geoms of spatial tendons, tendon spring lengths and stiffnesses) and in its problem
//! file (object pose, contact points, `mu_torsion`, moments, the object's centre of
//! mass), as a user who writes the same hand in millimetres would. The kinematics,
//! tendon moment arms, springs and the links' weight must then give the same grasp:
//! contact forces equal (torsional moments scaled), each joint torque and actuator
//! force scaled by its own unit (a torque by c, a tendon's force by 1), σ equal once
//! the weights carry the units, the same status — on the linear and the exact cones.
//!
//! Object frame: the object frame moved and turned (its pose, and the contacts, wrench
//! and centre of mass written in it) gives the same torques on the exact cones. The
//! inscribed polygons are laid out in contact frames built from the normal's
//! coordinates in the object frame (docs/geometry.md), so a linearised answer turns
//! with the frame: only its status is compared.

mod common;

use common::run;
use grasp_torque::{load, parse_problem_at, Backend, Cones, GraspProblem, TorqueLimit};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

/// How an attribute's numbers change: `(element, its tag, attribute)` to the factors of
/// its numbers in order (the last repeating), or `None` to leave them.
type Factors<'a> = dyn Fn(&str, &str, &str) -> Option<Vec<f64>> + 'a;

/// `text` with the numbers of its attributes multiplied as `factors` says.
fn rescale_xml(text: &str, factors: &Factors<'_>) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(open) = rest.find('<') {
        out.push_str(&rest[..open]);
        rest = &rest[open..];
        // Comments, declarations and closing tags are copied as they are.
        let skip_to = if rest.starts_with("<!--") {
            Some("-->")
        } else if rest.starts_with("<?") || rest.starts_with("<!") || rest.starts_with("</") {
            Some(">")
        } else {
            None
        };
        if let Some(end) = skip_to {
            let at = rest.find(end).expect("a closed markup") + end.len();
            out.push_str(&rest[..at]);
            rest = &rest[at..];
            continue;
        }
        let close = rest.find('>').expect("a closed tag");
        let tag = &rest[..close];
        rest = &rest[close..];
        let name_end = tag[1..]
            .find(|c: char| c.is_whitespace() || c == '/')
            .map_or(tag.len(), |i| i + 1);
        let element = &tag[1..name_end];
        out.push_str(&tag[..name_end]);
        let mut attrs = &tag[name_end..];
        // `name="value"` pairs (or single quotes), whitespace kept.
        while let Some(eq) = attrs.find('=') {
            let before = &attrs[..eq];
            let name = before.trim().rsplit(char::is_whitespace).next().unwrap();
            out.push_str(before);
            out.push('=');
            let after = &attrs[eq + 1..];
            let open = after.find(['"', '\'']).expect("a quoted value");
            let quote = &after[open..=open];
            let end = after[open + 1..].find(quote).expect("a closing quote") + open + 1;
            let value = &after[open + 1..end];
            out.push_str(&after[..=open]);
            match factors(element, tag, name) {
                Some(f) => {
                    let scaled: Vec<String> = value
                        .split_whitespace()
                        .enumerate()
                        .map(|(i, v)| {
                            let v: f64 = v.parse().expect("a number");
                            format!("{:?}", v * f[i.min(f.len() - 1)])
                        })
                        .collect();
                    out.push_str(&scaled.join(" "));
                }
                None => out.push_str(value),
            }
            out.push_str(quote);
            attrs = &after[end + 1..];
        }
        out.push_str(attrs);
    }
    out.push_str(rest);
    out
}

/// A copy of the hand's model folder (its XML and URDF files) with every length
/// multiplied by `c`, in a fresh folder.
fn rescaled_model_dir(model: &Path, c: f64, tag: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("grasp-units-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let urdf = |e: &str, _: &str, a: &str| (e == "origin" && a == "xyz").then(|| vec![c]);
    for entry in std::fs::read_dir(model.parent().unwrap()).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let scaled = match path.extension().and_then(|e| e.to_str()) {
            Some("xml") => rescale_xml(&text, &mjcf_lengths(&text, c, true)),
            Some("urdf") => rescale_xml(&text, &urdf),
            _ => continue,
        };
        std::fs::write(dir.join(path.file_name().unwrap()), scaled).unwrap();
    }
    dir
}

/// The factors that a change of the unit of length by c gives an MJCF file's numbers
/// (`springs`: also its springs' stiffnesses). A length is multiplied by c: positions,
/// sizes, a slide joint's `ref`, `springref` and `range`, a tendon's length, so a
/// fixed tendon's coefficient on a hinge (a length per radian; on a slide it has no
/// unit). A couplings's polynomial coefficient k carries the unit of its joint or
/// tendon over the k-th power of the other's. A stiffness per length (a tendon's or a
/// slide joint's spring) is divided by c; a hinge's (N·m/rad) multiplied, being a
/// torque. The slide joints are found by their tags' `type="slide"` in `text`.
fn mjcf_lengths(
    text: &str,
    c: f64,
    springs: bool,
) -> impl Fn(&str, &str, &str) -> Option<Vec<f64>> {
    let attr = |tag: &str, name: &str| {
        let key = format!(" {name}=\"");
        tag.find(&key).map(|i| {
            let v = &tag[i + key.len()..];
            v[..v.find('"').unwrap()].to_string()
        })
    };
    let slides: Vec<String> = text
        .split("<joint")
        .skip(1)
        .map(|t| t.split('>').next().unwrap())
        .filter(|t| t.contains("type=\"slide\""))
        .filter_map(|t| attr(t, "name"))
        .collect();
    let unit = move |joint: Option<String>| match joint {
        Some(j) if slides.contains(&j) => c,
        _ => 1.0,
    };
    move |element: &str, tag: &str, name: &str| {
        let slide = element == "joint" && tag.contains("type=\"slide\"");
        let powers = |top: f64, base: f64| (0..5).map(|k| top / base.powi(k)).collect();
        match (element, name) {
            (_, "pos" | "fromto" | "springlength") | ("geom" | "site", "size") => Some(vec![c]),
            ("joint", "ref" | "springref" | "range") if slide => Some(vec![c]),
            ("tendon" | "spatial" | "fixed", "stiffness") if springs => Some(vec![1.0 / c]),
            ("joint", "stiffness") if springs => Some(vec![if slide { 1.0 / c } else { c }]),
            // A fixed tendon's term: `<joint joint="…" coef="…"/>`.
            ("joint", "coef") => Some(vec![c / unit(attr(tag, "joint"))]),
            ("tendon", "polycoef") => Some(powers(c, c)),
            ("joint", "polycoef") => {
                let (u1, u2) = (unit(attr(tag, "joint1")), unit(attr(tag, "joint2")));
                Some(powers(u1, u2))
            }
            _ => None,
        }
    }
}

fn scale_array(v: &mut Value, c: f64) {
    for x in v.as_array_mut().unwrap() {
        *x = (x.as_f64().unwrap() * c).into();
    }
}

/// The problem file with its lengths multiplied by `c`, its model the rescaled copy;
/// without weights and limits (the test gives them in the new units).
fn rescaled_problem(fixture: &str, c: f64, tag: &str) -> GraspProblem {
    let path = repo(fixture);
    let mut file: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let model = path
        .parent()
        .unwrap()
        .join(file["hand"]["model"].as_str().unwrap());
    let dir = rescaled_model_dir(&model, c, tag);
    file["hand"]["model"] = dir
        .join(model.file_name().unwrap())
        .to_str()
        .unwrap()
        .into();
    if let Some(p) = file.pointer_mut("/object_pose/position") {
        scale_array(p, c);
    }
    if let Some(p) = file.pointer_mut("/object/center_of_mass") {
        scale_array(p, c);
    }
    for contact in file["contacts"].as_array_mut().unwrap() {
        if let Some(p) = contact.get_mut("position") {
            scale_array(p, c);
        }
        if let Some(t) = contact.get_mut("mu_torsion") {
            *t = (t.as_f64().unwrap() * c).into();
        }
    }
    if let Some(w) = file.get_mut("wrench") {
        for m in &mut w.as_array_mut().unwrap()[3..] {
            *m = (m.as_f64().unwrap() * c).into();
        }
    }
    let obj = file.as_object_mut().unwrap();
    obj.remove("torque_limits");
    obj.remove("torque_weights");
    let problem = parse_problem_at(&file.to_string(), &dir)
        .unwrap_or_else(|e| panic!("{fixture} at {c}: {e}"))
        .problem;
    std::fs::remove_dir_all(&dir).unwrap();
    problem
}

/// The unit of each row of `a` in `b`: the ratio of the rows' largest entries on the
/// columns `cols`, checked to be one of `allowed` for every such entry.
fn row_units(
    a: &grasp_torque::Matrix,
    b: &grasp_torque::Matrix,
    cols: &[usize],
    allowed: &[f64],
) -> Vec<f64> {
    (0..a.nrows())
        .map(|i| {
            let big = cols.iter().fold(0.0f64, |m, &k| m.max(a[(i, k)].abs()));
            let unit = allowed
                .iter()
                .copied()
                .find(|&u| {
                    cols.iter()
                        .all(|&k| (b[(i, k)] - u * a[(i, k)]).abs() <= 1e-12 * u * big)
                })
                .unwrap_or_else(|| {
                    let ra: Vec<f64> = cols.iter().map(|&k| a[(i, k)]).collect();
                    let rb: Vec<f64> = cols.iter().map(|&k| b[(i, k)]).collect();
                    panic!("row {i}: no unit among {allowed:?}: {ra:?} {rb:?}")
                });
            unit
        })
        .collect()
}

#[test]
fn hands_written_in_other_units_give_the_same_grasp() {
    let fixtures = [
        "fixtures/hands/allegro-weighed.json",
        "fixtures/hands/ability-tripod.json",
        "fixtures/hands/shadow-tripod.json",
        "fixtures/hands/aero-pinch.json",
        "fixtures/hands/aero-pull.json",
    ];
    let (mut checked, mut worst) = (0, 0.0f64);
    for fixture in fixtures {
        let p = load(repo(fixture)).unwrap().problem;
        // The columns of force components (not torsional moments), per contact.
        let mut forces = Vec::new();
        let mut moments = Vec::new();
        let mut k = 0;
        for contact in &p.contacts {
            let d = contact.dim();
            forces.extend(k..k + d.min(3));
            moments.extend(k + 3..k + d);
            k += d;
        }
        for (i, c) in [1e-3, 1e3, 1e-6, 1e6].into_iter().enumerate() {
            let mut q = rescaled_problem(fixture, c, &i.to_string());
            assert_eq!(q.joint_names, p.joint_names, "{fixture}");
            // A revolute joint's torque carries a length; a prismatic one's does not.
            let joint = row_units(
                &p.jacobian_transpose,
                &q.jacobian_transpose,
                &forces,
                &[c, 1.0],
            );
            // An actuator's force is its joints' torque over its arm: a gear carries
            // no length, a tendon's arm does.
            let unit: Vec<f64> = match (&p.transmission, &q.transmission) {
                (Some(t), Some(s)) => {
                    let (tt, st) = (t.matrix.transpose(), s.matrix.transpose());
                    let all: Vec<usize> = (0..tt.ncols()).collect();
                    let arm = row_units(&tt, &st, &all, &[c, 1.0]);
                    (0..tt.nrows())
                        .map(|a| {
                            let j = (0..tt.ncols())
                                .max_by(|&x, &y| tt[(a, x)].abs().total_cmp(&tt[(a, y)].abs()))
                                .unwrap();
                            joint[j] / arm[a]
                        })
                        .collect()
                }
                (None, None) => joint.clone(),
                _ => panic!("{fixture}: a transmission in one unit only"),
            };
            if let (Some(a), Some(b)) = (&p.passive_torque, &q.passive_torque) {
                let big = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for j in 0..a.len() {
                    assert!(
                        (b[j] - joint[j] * a[j]).abs() <= 1e-9 * c * big,
                        "{fixture} at {c}: passive torque {j}: {} against {}",
                        b[j],
                        joint[j] * a[j]
                    );
                }
            }
            // Weights and limits in the new units, so that σ stays as it was. Weights
            // are within a ratio of 1e8 of each other (the input domain): a hand whose
            // actuators pull tendons (forces) and turn joints (torques) is solved at
            // scales up to 1e±4 only; its arms and springs were checked above.
            let spread = unit
                .iter()
                .fold(1.0f64, |m, u| m.max(u / unit[0]).max(unit[0] / u));
            if spread * spread > 1e8 {
                continue;
            }
            let weights = p.torque_weights.clone().unwrap_or(vec![1.0; unit.len()]);
            q.torque_weights = Some(
                weights
                    .iter()
                    .zip(&unit)
                    .map(|(w, u)| w / (u * u))
                    .collect(),
            );
            q.torque_limits = p.torque_limits.as_ref().map(|l| {
                l.iter()
                    .zip(&unit)
                    .map(|(l, &u)| l.map(|l: TorqueLimit| l.scaled(u)))
                    .collect()
            });
            for cones in [Cones::Linear, Cones::Exact] {
                let native = Backend::ActiveSet;
                let (a, b) = (run(&p, native, cones), run(&q, native, cones));
                let what = format!("{fixture} at {c}, {cones:?}");
                assert_eq!(a.status, b.status, "{what}");
                assert!(a.is_optimal(), "{what}: {:?}", a.status);
                assert!(
                    (b.objective - a.objective).abs() <= 1e-9 * a.objective,
                    "{what}: σ {} against {}",
                    b.objective,
                    a.objective
                );
                let big = a
                    .torque
                    .iter()
                    .zip(&unit)
                    .fold(0.0f64, |m, (t, u)| m.max((t * u).abs()));
                // Each input moves by an ulp in the other unit; 1e-9 leaves room for the
                // grasps' conditioning (the worst seen is printed).
                for (j, ((x, y), u)) in a.torque.iter().zip(&b.torque).zip(&unit).enumerate() {
                    worst = worst.max((y - x * u).abs() / big);
                    assert!(
                        (y - x * u).abs() <= 1e-9 * big,
                        "{what}: u[{j}] {y} against {}",
                        x * u
                    );
                }
                let fa = &a.contact_forces;
                let fb = &b.contact_forces;
                let fbig = forces.iter().fold(0.0f64, |m, &k| m.max(fa[k].abs()));
                for &k in &forces {
                    assert!((fb[k] - fa[k]).abs() <= 1e-9 * fbig, "{what}: f[{k}]");
                }
                for &k in &moments {
                    assert!(
                        (fb[k] - c * fa[k]).abs() <= 1e-9 * c * fbig,
                        "{what}: mz[{k}]"
                    );
                }
                checked += 1;
            }
        }
    }
    eprintln!("{checked} solves in other units: actuator forces and torques within {worst:.1e} of the largest");
    // Every scale of the three hands whose forces share a unit, 1e±3 of the Aero's.
    assert_eq!(checked, (3 * 4 + 2 * 2) * 2);
}

#[test]
fn rescaling_touches_only_the_lengths() {
    let text = concat!(
        "<!-- pos=\"1\" --><mujoco><body pos='1 2 3' name=\"pos\">\n",
        "<geom size=\"0.5\" type=\"box\"/><joint name=\"h\" stiffness=\"2\" ref=\"3\"/>",
        "<joint name=\"s\" type=\"slide\" ref=\"0.5\" stiffness=\"2\"/></body>",
        "<tendon><fixed><joint joint=\"h\" coef=\"1\"/><joint joint=\"s\" coef=\"1\"/></fixed></tendon>",
        "<equality><joint joint1=\"s\" joint2=\"h\" polycoef=\"1 2 3 0 0\"/></equality></mujoco>"
    );
    assert_eq!(
        rescale_xml(text, &mjcf_lengths(text, 10.0, true)),
        concat!(
            "<!-- pos=\"1\" --><mujoco><body pos='10.0 20.0 30.0' name=\"pos\">\n",
            "<geom size=\"5.0\" type=\"box\"/><joint name=\"h\" stiffness=\"20.0\" ref=\"3\"/>",
            "<joint name=\"s\" type=\"slide\" ref=\"5.0\" stiffness=\"0.2\"/></body>",
            "<tendon><fixed><joint joint=\"h\" coef=\"10.0\"/><joint joint=\"s\" coef=\"1.0\"/></fixed></tendon>",
            "<equality><joint joint1=\"s\" joint2=\"h\" polycoef=\"10.0 20.0 30.0 0.0 0.0\"/></equality></mujoco>"
        )
    );
}

/// Spatial tendons wrap the same in any units: on the Aero hand and the random spatial
/// hands (sphere and cylinder wraps, side sites, pulleys, slide joints), with every
/// length multiplied by c from 1e-9 to 1e9, each tendon's length is c times its length
/// and each arm c times its arm on a hinge (an arm on a slide joint has no unit), at
/// configurations spread over the joints' ranges.
#[test]
fn spatial_tendons_wrap_the_same_in_any_units() {
    let mut models = vec![repo("fixtures/mjcf/menagerie/aero_right.xml")];
    models.extend((0..8).map(|i| repo(&format!("fixtures/mjcf/gravity/spatial-{i}.xml"))));
    let mut compared = 0;
    for path in models {
        // The random hands' slide joints may take a hinge class's `ref` (an angle, read
        // as a length); the rescaling sees a joint's own attributes only, so each slide
        // joint gets its own, 0 where it had none, in both units.
        let text = std::fs::read_to_string(&path)
            .unwrap()
            .split("<joint ")
            .enumerate()
            .map(|(i, t)| {
                let tag = t.split('>').next().unwrap();
                if i > 0 && tag.contains("type=\"slide\"") && !tag.contains(" ref=") {
                    format!("ref=\"0\" {t}")
                } else {
                    t.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("<joint ");
        let name = path.file_name().unwrap().to_str().unwrap();
        let robot = grasp_torque::Robot::parse_mjcf(&text, name, None).unwrap();
        assert!(!robot.tendons.is_empty(), "{name}");
        // Geometry only: at 1e-9 the springs' stiffnesses would leave the input domain.
        for c in [1e-9, 1e-6, 1e-3, 1e3, 1e6, 1e9] {
            let scaled = grasp_torque::Robot::parse_mjcf(
                &rescale_xml(&text, &mjcf_lengths(&text, c, false)),
                name,
                None,
            )
            .unwrap_or_else(|e| panic!("{name} at {c}: {e}"));
            let hinge = |j: usize| robot.joints[j].kind.rotates();
            for k in 0..5 {
                // Positions spread over ±0.6 rad (a slide joint's in the file's length).
                let q: Vec<f64> = robot
                    .independent
                    .iter()
                    .enumerate()
                    .map(|(i, &j)| {
                        let t = 0.6 * (((i * 7 + k * 3) % 11) as f64 / 5.0 - 1.0);
                        if hinge(j) {
                            t
                        } else {
                            0.01 * t
                        }
                    })
                    .collect();
                let qs: Vec<f64> = q
                    .iter()
                    .zip(&robot.independent)
                    .map(|(&v, &j)| if hinge(j) { v } else { c * v })
                    .collect();
                let (pose, spose) = (robot.pose(&q), scaled.pose(&qs));
                for t in 0..robot.tendons.len() {
                    let what = format!("{name} tendon {t} at {c}, configuration {k}");
                    let (l, arms) = robot.tendon_moments(t, &pose).unwrap();
                    let (ls, sarms) = scaled.tendon_moments(t, &spose).unwrap();
                    assert!(
                        (ls - c * l).abs() <= 1e-12 * c * l,
                        "{what}: length {ls} against {}",
                        c * l
                    );
                    let big = arms.iter().fold(0.0f64, |m, a| m.max(a.1.abs()));
                    for ((j, a), (js, s)) in arms.iter().zip(&sarms) {
                        assert_eq!(j, js);
                        let unit = if hinge(*j) { c } else { 1.0 };
                        assert!(
                            (s - unit * a).abs() <= 1e-12 * unit * big,
                            "{what}: arm on joint {j}: {s} against {}",
                            unit * a
                        );
                    }
                    compared += 1;
                }
            }
        }
    }
    assert!(compared > 400, "{compared}");
}

/// `file` with its object frame moved by `t` and turned by `r` (both in the old object
/// frame): the object pose composed with them, and what is written in the object
/// frame (contact points and normals, the wrench about the origin, the centre of
/// mass) written in the new one.
fn moved_object_frame(file: &mut Value, r: &UnitQuaternion<f64>, t: &Vector3<f64>) {
    let vector = |v: &Value| {
        Vector3::from_iterator(v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
    };
    let json = |v: Vector3<f64>| Value::from(v.iter().copied().collect::<Vec<_>>());
    let back = r.inverse();
    let pose = file.pointer("/object_pose").cloned().unwrap_or_default();
    let p0 = pose.get("position").map_or(Vector3::zeros(), vector);
    let q0 = pose
        .get("quaternion")
        .map_or(UnitQuaternion::identity(), |q| {
            let q = q
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect::<Vec<_>>();
            UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
        });
    let q = q0 * r;
    file["object_pose"] = serde_json::json!({
        "position": json(p0 + q0 * t),
        "quaternion": [q.w, q.i, q.j, q.k],
    });
    for contact in file["contacts"].as_array_mut().unwrap() {
        if contact.get("frame").and_then(Value::as_str) == Some("link") {
            continue;
        }
        if let Some(p) = contact.get_mut("position") {
            *p = json(back * (vector(p) - t));
        }
        if let Some(n) = contact.get_mut("normal") {
            *n = json(back * vector(n));
        }
    }
    if let Some(w) = file.get_mut("wrench") {
        let w6: Vec<f64> = w
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let (f, m) = (
            Vector3::from_column_slice(&w6[..3]),
            Vector3::from_column_slice(&w6[3..]),
        );
        let (f2, m2) = (back * f, back * (m - t.cross(&f)));
        *w = Value::from(f2.iter().chain(m2.iter()).copied().collect::<Vec<_>>());
    }
    if let Some(c) = file.pointer_mut("/object/center_of_mass") {
        *c = json(back * (vector(c) - t));
    }
}

#[test]
fn hands_hold_the_same_in_any_object_frame() {
    let fixtures = [
        "fixtures/hands/allegro-pinch.json",
        "fixtures/hands/allegro-weighed.json",
        "fixtures/hands/ability-tripod.json",
        "fixtures/hands/shadow-tripod.json",
        "fixtures/hands/aero-pull.json",
    ];
    let mut compared = 0;
    for fixture in fixtures {
        let path = repo(fixture);
        let text = std::fs::read_to_string(&path).unwrap();
        let base = path.parent().unwrap();
        let p = parse_problem_at(&text, base).unwrap().problem;
        let native = Backend::ActiveSet;
        let (exact, linear) = (
            run(&p, native, Cones::Exact),
            run(&p, native, Cones::Linear),
        );
        assert!(exact.is_optimal(), "{fixture}");
        for k in 0..4 {
            // Turns and shifts of the size of the grasp, fixed by k.
            let x = k as f64;
            let r = UnitQuaternion::from_euler_angles(0.7 * x + 0.3, -1.1 * x + 0.5, 2.3 * x - 1.0);
            let t = Vector3::new(0.03 * x - 0.04, 0.05 - 0.02 * x, 0.01 * x);
            let mut file: Value = serde_json::from_str(&text).unwrap();
            moved_object_frame(&mut file, &r, &t);
            let q = parse_problem_at(&file.to_string(), base).unwrap().problem;
            let what = format!("{fixture}, frame {k}");
            let b = run(&q, native, Cones::Exact);
            assert_eq!(b.status, exact.status, "{what}");
            let big = exact.torque.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (j, (x, y)) in exact.torque.iter().zip(&b.torque).enumerate() {
                // Newton stops at a 1e-11 step: the two answers are each that close.
                assert!(
                    (x - y).abs() <= 1e-9 * big,
                    "{what}: τ[{j}] {y} against {x}"
                );
            }
            assert!(
                (b.objective - exact.objective).abs() <= 1e-9 * exact.objective,
                "{what}"
            );
            assert_eq!(
                run(&q, native, Cones::Linear).status,
                linear.status,
                "{what}"
            );
            compared += 1;
        }
    }
    assert_eq!(compared, 20);
}
