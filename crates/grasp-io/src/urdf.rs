//! Robot descriptions in URDF: the kinematic tree of a hand, its independent joints and
//! mimic couplings, forward kinematics and joint frames.
//!
//! The file is read with `roxmltree`, which gives every element's line for messages.
//! Only what statics uses is read: links, and each joint's type, `<origin>`, `<axis>`,
//! `<parent>`, `<child>`, `<limit>` (with neither `effort` nor `velocity` required)
//! and `<mimic>`, each at most once and every number checked; and each `<inertial>`'s
//! mass and centre of mass. Malformed or duplicated inertial data loads, with a
//! warning (the link's weight is then unknown, an error only when gravity is asked
//! for); `<visual>`, `<collision>`, `<transmission>`, `<gazebo>` and the rest are
//! never read, so meshes are never opened.
//!
//! Frames follow the URDF specification: a joint's frame is its parent link's frame
//! moved by `<origin xyz rpy>` (roll, pitch, yaw about the fixed x, y, z axes, so
//! `R = Rz(yaw) Ry(pitch) Rx(roll)`); the joint moves its child link about (revolute,
//! continuous) or along (prismatic) its unit `<axis>`, given in the joint frame. A mimic
//! joint follows `q = multiplier · q_leader + offset`; chains of mimics are resolved to
//! the independent joint at their end.

use crate::frame::{Isometry3, UnitQuaternion, Vector3};
use crate::mass::LinkMass;
use crate::tendon::SpatialTendon;
use grasp_core::error::ProblemError;
use std::collections::HashMap;
use std::path::Path;

/// Most links a robot description may have: far above any hand (a humanoid has about
/// a hundred), and it bounds the work of a hostile file.
pub const MAX_LINKS: usize = 10_000;

/// Deepest element nesting read: a URDF nests five or six levels.
pub const MAX_DEPTH: usize = 64;

/// The kind of a joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about the axis, within limits.
    Revolute,
    /// Rotation about the axis, without limits.
    Continuous,
    /// Translation along the axis.
    Prismatic,
    /// No motion: folded into the chain.
    Fixed,
}

impl JointKind {
    /// The URDF name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Revolute => "revolute",
            Self::Continuous => "continuous",
            Self::Prismatic => "prismatic",
            Self::Fixed => "fixed",
        }
    }

    /// Whether the joint rotates (revolute or continuous).
    pub fn rotates(self) -> bool {
        matches!(self, Self::Revolute | Self::Continuous)
    }
}

/// `q = multiplier · q_leader + offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mimic {
    /// The joint followed (index into [`Robot::joints`]), as written in the file.
    pub leader: usize,
    /// Multiplier (default 1).
    pub multiplier: f64,
    /// Offset, in radians or metres (default 0).
    pub offset: f64,
}

/// How a moving joint follows the independent coordinates: `q = multiplier ·
/// q_ind[independent] + offset`, with mimic chains resolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coupling {
    /// Index into [`Robot::independent`].
    pub independent: usize,
    /// Product of the multipliers along the mimic chain (1 for an independent joint).
    pub multiplier: f64,
    /// Offset accumulated along the chain (0 for an independent joint).
    pub offset: f64,
}

/// One joint of the description.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Its name.
    pub name: String,
    /// Its kind.
    pub kind: JointKind,
    /// The joint frame in the parent link's frame (`<origin>`).
    pub origin: Isometry3,
    /// The unit axis in the joint frame (normalised from `<axis xyz>`).
    pub axis: Vector3,
    /// Parent link (index into [`Robot::links`]).
    pub parent: usize,
    /// Child link.
    pub child: usize,
    /// The joint's torque limit, N·m or N: a URDF's `<limit effort>` when given,
    /// finite and positive (`|τ| ≤ effort`); an MJCF joint's `actuatorfrcrange` when
    /// limited (MuJoCo clamps the total actuator force on the joint to it).
    pub effort: Option<grasp_core::TorqueLimit>,
    /// `<limit lower>`, when the joint has a finite one.
    pub lower: Option<f64>,
    /// `<limit upper>`, when the joint has a finite one.
    pub upper: Option<f64>,
    /// `<mimic>`, when the joint follows another.
    pub mimic: Option<Mimic>,
    /// Line of the `<joint>` element.
    pub line: u32,
}

/// A parsed, checked kinematic tree.
#[derive(Clone, Debug)]
pub struct Robot {
    /// `<robot name>`.
    pub name: String,
    /// The file, as given, for messages.
    pub source: String,
    /// Link names, in file order.
    pub links: Vec<String>,
    /// Joints, in file order.
    pub joints: Vec<Joint>,
    /// The root link: the one that is no joint's child.
    pub root: usize,
    /// The joints that are neither fixed nor mimic, in file order: the coordinates
    /// `q_ind` a configuration is given in.
    pub independent: Vec<usize>,
    /// Per joint: how it follows `q_ind` (`None` for fixed joints).
    pub coupling: Vec<Option<Coupling>>,
    /// What was loaded but ignored, one line each (malformed or duplicated inertial
    /// data, an effort of zero).
    pub warnings: Vec<String>,
    /// Named frames on links (MJCF `<site>`; none in a URDF).
    pub sites: Vec<Site>,
    /// Actuators (MJCF `<actuator>`; none in a URDF, whose joints are driven one to
    /// one).
    pub actuators: Vec<Actuator>,
    /// Spatial tendons that actuators pull on (MJCF `<tendon><spatial>`; none in a
    /// URDF).
    pub tendons: Vec<SpatialTendon>,
    /// Springs on joints and tendons (MJCF `stiffness`; none in a URDF): the passive
    /// torques of [`Robot::passive_torques`].
    pub springs: Vec<crate::tendon::Spring>,
    /// Per link: its mass and centre of mass (URDF `<inertial>`; MJCF `<inertial>` or
    /// its geoms, as MuJoCo's compiler computes them), for
    /// [`Robot::gravity_torques`].
    pub masses: Vec<LinkMass>,
    /// The acceleration of gravity in the root frame the file gives (MJCF `<option
    /// gravity>`, default `0 0 −9.81`): `None` for a URDF, which has none, and for a
    /// floating MJCF hand, whose orientation in the world the file does not fix.
    pub gravity: Option<Vector3>,
    /// Per link: the joint whose child it is (`None` for the root).
    pub(crate) parent_joint: Vec<Option<usize>>,
    /// Links from the root outwards: every parent comes before its children.
    pub(crate) order: Vec<usize>,
    link_lines: Vec<u32>,
}

/// A named frame fixed to a link (an MJCF `<site>`).
#[derive(Clone, Debug, PartialEq)]
pub struct Site {
    /// Its name.
    pub name: String,
    /// The link it is on.
    pub link: usize,
    /// Its frame in the link's frame; its z axis is a contact's default normal.
    pub frame: Isometry3,
    /// Line of the element.
    pub line: u32,
}

/// Where an actuator's force limit comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LimitSource {
    /// `forcerange` (force-limited).
    Forcerange,
    /// `ctrlrange` times the gain of an actuator whose force is gain × ctrl.
    Ctrlrange,
    /// Neither applies: unlimited.
    None,
    /// The `actuatorfrcrange` of a joint that this actuator alone drives, which MuJoCo
    /// clamps the actuator's force on the joint to (`gear × u` within it), narrower
    /// than the actuator's own range or the only one.
    Actuatorfrcrange,
}

/// How an actuator's force moves the joints.
#[derive(Clone, Debug, PartialEq)]
pub enum Drive {
    /// Constant moment arms (index into [`Robot::joints`], value): the gear on a joint,
    /// the gear times the coefficients of a fixed tendon.
    Fixed(Vec<(usize, f64)>),
    /// `gear` times the moment arms of a spatial tendon (an index of
    /// [`Robot::tendons`]), which depend on the configuration.
    Tendon {
        /// The tendon.
        tendon: usize,
        /// The gear.
        gear: f64,
    },
}

/// One actuator: how its force u moves the joints.
#[derive(Clone, Debug, PartialEq)]
pub struct Actuator {
    /// Its name.
    pub name: String,
    /// The MJCF element (`motor`, `general`, `position`, …).
    pub kind: String,
    /// How its force moves the joints.
    pub drive: Drive,
    /// Its force range: `|u| ≤ t`, or `lower ≤ u ≤ upper` when not symmetric.
    pub limit: Option<grasp_core::TorqueLimit>,
    /// Where the limit comes from.
    pub limit_source: LimitSource,
    /// Line of the element.
    pub line: u32,
}

/// The frames of every link and joint at one configuration, in the root link's frame.
#[derive(Clone, Debug)]
pub struct Pose {
    /// Per link: its frame.
    pub links: Vec<Isometry3>,
    /// Per joint: its frame (the parent link's frame moved by `<origin>`, before the
    /// joint's own motion).
    pub joints: Vec<Isometry3>,
}

fn robot_error(file: &str, element: impl Into<String>, message: impl Into<String>) -> ProblemError {
    ProblemError::RobotModel {
        file: file.to_string(),
        element: element.into(),
        message: message.into(),
    }
}

/// Levenshtein distance, for "did you mean" lists.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

/// Up to three of `names` nearest to `name`, as a readable list.
pub fn nearest<'a>(name: &str, names: impl IntoIterator<Item = &'a str>) -> String {
    let mut scored: Vec<(usize, &str)> = names
        .into_iter()
        .map(|n| (edit_distance(name, n), n))
        .collect();
    scored.sort();
    scored.dedup();
    let list: Vec<String> = scored
        .iter()
        .take(3)
        .map(|(_, n)| format!("`{n}`"))
        .collect();
    if list.is_empty() {
        "there are none".into()
    } else {
        format!("nearest: {}", list.join(", "))
    }
}

/// A joint's `<limit>`; statics needs neither `effort` nor `velocity`, which the URDF
/// specification requires.
#[derive(Clone, Copy, Debug, Default)]
struct Limit {
    lower: Option<f64>,
    upper: Option<f64>,
    effort: Option<f64>,
}
const JOINT_TYPES: [&str; 7] = [
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
    "spherical",
];

/// The children of `<joint>` statics reads; each may appear once.
const JOINT_PARTS: [&str; 6] = ["origin", "axis", "parent", "child", "limit", "mimic"];

/// `<mimic>` as written: the leader by name.
struct RawMimic {
    joint: String,
    multiplier: f64,
    offset: f64,
}

/// A `<joint>` as written, its numbers checked; links and the leader by name.
struct RawJoint {
    name: String,
    kind: &'static str,
    origin: Isometry3,
    /// `<axis xyz>` (default `1 0 0`), not yet normalised.
    axis: Vector3,
    parent: String,
    child: String,
    limit: Limit,
    mimic: Option<RawMimic>,
    line: u32,
}

/// What the `roxmltree` pass reads: the links and joints with their lines, and
/// warnings.
struct Scan {
    /// `<robot name>` ("" if none).
    name: String,
    links: Vec<String>,
    link_lines: Vec<u32>,
    joints: Vec<RawJoint>,
    warnings: Vec<String>,
    /// Per link with an `<inertial>`: its mass.
    masses: HashMap<String, LinkMass>,
}

/// Numbers of an attribute, each finite, or an error naming the element.
fn numbers<const N: usize>(
    file: &str,
    at: &str,
    element: roxmltree::Node,
    attr: &str,
) -> Result<Option<[f64; N]>, ProblemError> {
    let Some(text) = element.attribute(attr) else {
        return Ok(None);
    };
    let values: Vec<Option<f64>> = text
        .split_whitespace()
        .map(|v| v.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect();
    match <[Option<f64>; N]>::try_from(values) {
        Ok(v) if v.iter().all(Option::is_some) => Ok(Some(v.map(|x| x.unwrap_or_default()))),
        _ => Err(robot_error(
            file,
            at,
            format!(
                "<{} {attr}=\"{text}\">: expected {N} finite number{}",
                element.tag_name().name(),
                if N == 1 { "" } else { "s" }
            ),
        )),
    }
}

/// `<robot version="major.minor">`; absent or malformed is 1.0, as urdfdom reads it.
fn version(robot: roxmltree::Node) -> (u32, u32) {
    robot
        .attribute("version")
        .and_then(|v| {
            let (major, minor) = v.trim().split_once('.')?;
            Some((major.parse().ok()?, minor.parse().ok()?))
        })
        .unwrap_or((1, 0))
}

/// A joint's `<origin>`: `xyz`, and `rpy` (roll, pitch, yaw about the fixed axes) or,
/// from URDF 1.1 on, `quat_xyzw` (normalised, as urdfdom does); an older file's
/// `quat_xyzw` is ignored, as urdfdom ignores it.
fn origin(
    file: &str,
    at: &str,
    e: roxmltree::Node,
    version: (u32, u32),
) -> Result<Isometry3, ProblemError> {
    let xyz = numbers::<3>(file, at, e, "xyz")?.unwrap_or_default();
    let rpy = numbers::<3>(file, at, e, "rpy")?;
    let quat = if version >= (1, 1) {
        numbers::<4>(file, at, e, "quat_xyzw")?
    } else {
        None
    };
    let rotation = match (rpy, quat) {
        (Some(_), Some(_)) => {
            return Err(robot_error(
                file,
                at,
                "<origin> has both rpy and quat_xyzw: give one",
            ))
        }
        (_, Some([x, y, z, w])) => {
            // Scaled first, so that no finite quaternion overflows its norm.
            let big = [x, y, z, w].iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if big == 0.0 {
                return Err(robot_error(
                    file,
                    at,
                    "<origin quat_xyzw=\"0 0 0 0\">: expected a nonzero quaternion",
                ));
            }
            UnitQuaternion::new_normalize(w / big, x / big, y / big, z / big)
        }
        (rpy, None) => {
            let [r, p, y] = rpy.unwrap_or_default();
            UnitQuaternion::from_euler_angles(r, p, y)
        }
    };
    Ok(Isometry3::from_parts(Vector3::from(xyz), rotation))
}

/// A `<joint>`'s parts, each checked; `at` names it in errors.
fn joint(
    file: &str,
    at: &str,
    e: roxmltree::Node,
    version: (u32, u32),
    line: impl Fn(roxmltree::Node) -> u32,
) -> Result<RawJoint, ProblemError> {
    let kind = e.attribute("type").unwrap_or("");
    let Some(kind) = JOINT_TYPES.iter().find(|&&t| t == kind) else {
        return Err(robot_error(
            file,
            at,
            format!(
                "unknown joint type `{kind}` (expected one of {})",
                JOINT_TYPES.join(", ")
            ),
        ));
    };
    let mut parts: [Option<roxmltree::Node>; JOINT_PARTS.len()] = [None; JOINT_PARTS.len()];
    for c in e.children().filter(|n| n.is_element()) {
        let tag = c.tag_name().name();
        if let Some(k) = JOINT_PARTS.iter().position(|&p| p == tag) {
            if let Some(first) = parts[k] {
                return Err(robot_error(
                    file,
                    at,
                    format!(
                        "a second <{tag}> (line {}; the first is on line {})",
                        line(c),
                        line(first)
                    ),
                ));
            }
            parts[k] = Some(c);
        }
    }
    let [origin_e, axis_e, parent_e, child_e, limit_e, mimic_e] = parts;
    let link_of = |part: &str, e: Option<roxmltree::Node>| {
        e.and_then(|c| c.attribute("link"))
            .map(str::to_string)
            .ok_or_else(|| robot_error(file, at, format!("no <{part} link=\"…\"/> element")))
    };
    let parent = link_of("parent", parent_e)?;
    let child = link_of("child", child_e)?;
    let origin = match origin_e {
        Some(c) => origin(file, at, c, version)?,
        None => Isometry3::identity(),
    };
    let axis = match axis_e {
        Some(c) => numbers::<3>(file, at, c, "xyz")?,
        None => None,
    }
    .map_or_else(Vector3::x, Vector3::from);
    let mut limit = Limit::default();
    if let Some(c) = limit_e {
        let one = |a| numbers::<1>(file, at, c, a).map(|v| v.map(|[x]| x));
        limit = Limit {
            lower: one("lower")?,
            upper: one("upper")?,
            effort: one("effort")?,
        };
        one("velocity")?;
        if limit.effort.is_some_and(|e| e < 0.0) {
            return Err(robot_error(
                file,
                at,
                format!(
                    "<limit effort=\"{}\"> is negative",
                    c.attribute("effort").unwrap_or("")
                ),
            ));
        }
    }
    let mimic = match mimic_e {
        None => None,
        Some(c) => {
            let leader = c.attribute("joint").ok_or_else(|| {
                robot_error(
                    file,
                    at,
                    "<mimic> has no joint attribute (the joint it follows)",
                )
            })?;
            Some(RawMimic {
                joint: leader.to_string(),
                multiplier: numbers::<1>(file, at, c, "multiplier")?.map_or(1.0, |[m]| m),
                offset: numbers::<1>(file, at, c, "offset")?.map_or(0.0, |[o]| o),
            })
        }
    };
    Ok(RawJoint {
        name: String::new(),
        kind,
        origin,
        axis,
        parent,
        child,
        limit,
        mimic,
        line: line(e),
    })
}

fn scan(text: &str, file: &str) -> Result<Scan, ProblemError> {
    let doc = roxmltree::Document::parse(text)
        .map_err(|e| robot_error(file, "(document)", format!("not well-formed XML: {e}")))?;
    let robot = doc.root_element();
    let newlines = newline_offsets(text);
    let line = |n: roxmltree::Node| line_at(&newlines, n.range().start);
    if robot.tag_name().name() != "robot" {
        return Err(robot_error(
            file,
            format!("<{}> (line {})", robot.tag_name().name(), line(robot)),
            "expected a <robot> element at the top level (a URDF)",
        ));
    }
    // A URDF nests five or six levels; the same bound as an MJCF file's.
    let mut stack = vec![(robot, 1usize)];
    while let Some((node, depth)) = stack.pop() {
        if depth > MAX_DEPTH {
            return Err(robot_error(
                file,
                format!("<{}> (line {})", node.tag_name().name(), line(node)),
                format!("elements nested more than {MAX_DEPTH} deep"),
            ));
        }
        stack.extend(
            node.children()
                .filter(|n| n.is_element())
                .map(|n| (n, depth + 1)),
        );
    }
    let version = version(robot);
    let mut links = Vec::new();
    let mut link_lines = Vec::new();
    let mut joints = Vec::new();
    let mut first_line: [HashMap<&str, u32>; 2] = [HashMap::new(), HashMap::new()];
    let mut warnings = Vec::new();
    let mut masses = HashMap::new();
    // <material>, <transmission>, <gazebo>, …: nothing statics reads.
    for e in robot
        .children()
        .filter(|n| n.has_tag_name("link") || n.has_tag_name("joint"))
    {
        let tag = e.tag_name().name();
        let Some(name) = e.attribute("name") else {
            return Err(robot_error(
                file,
                format!("<{tag}> (line {})", line(e)),
                "has no name attribute",
            ));
        };
        let at = format!("<{tag} name=\"{name}\"> (line {})", line(e));
        if let Some(first) = first_line[usize::from(tag == "joint")].insert(name, line(e)) {
            return Err(robot_error(
                file,
                at,
                format!("a second {tag} of this name (the first is on line {first})"),
            ));
        }
        if tag == "joint" {
            let mut j = joint(file, &at, e, version, line)?;
            j.name = name.to_string();
            joints.push(j);
            continue;
        }
        if links.len() == MAX_LINKS {
            return Err(robot_error(
                file,
                at,
                format!("more than {MAX_LINKS} links; a hand has far fewer"),
            ));
        }
        links.push(name.to_string());
        link_lines.push(line(e));
        // Only the mass and its centre: <visual> and <collision> are never read, so
        // meshes are never opened.
        let mut inertials = 0;
        for c in e.children().filter(|c| c.has_tag_name("inertial")) {
            inertials += 1;
            let mass = inertial_mass(c)
                .map_err(|bad| format!("<inertial> on line {} is malformed ({bad})", line(c)));
            if let Err(why) = &mass {
                warnings.push(format!(
                    "{file}: {at}: {why}: the link's weight is unknown (an error only if gravity is asked for)"
                ));
            } else if let Some(bad) = malformed_tensor(c) {
                warnings.push(format!(
                    "{file}: {at}: <inertial> on line {} has a malformed {bad}; ignored, since rotational inertia does not enter statics",
                    line(c)
                ));
            }
            masses.insert(
                name.to_string(),
                mass.map_or_else(LinkMass::Unknown, |(mass, com)| LinkMass::Known {
                    mass,
                    com,
                }),
            );
        }
        if inertials > 1 {
            warnings.push(format!(
                "{file}: {at}: {inertials} <inertial> elements: the link's weight is unknown (an error only if gravity is asked for)"
            ));
            masses.insert(
                name.to_string(),
                LinkMass::Unknown(format!("{inertials} <inertial> elements")),
            );
        }
    }
    Ok(Scan {
        name: robot.attribute("name").unwrap_or("").to_string(),
        links,
        link_lines,
        joints,
        warnings,
        masses,
    })
}

/// Why `<tag attr>` of an `<inertial>` is not one finite number, if it is not.
fn inertial_number(e: roxmltree::Node, tag: &str, attr: &str) -> Result<f64, String> {
    let v = e
        .children()
        .find(|c| c.has_tag_name(tag))
        .and_then(|c| c.attribute(attr));
    match v.map(|s| s.trim().parse::<f64>()) {
        Some(Ok(x)) if x.is_finite() => Ok(x),
        Some(_) => Err(format!("<{tag} {attr}=\"{}\">", v.unwrap_or(""))),
        None => Err(format!("no <{tag} {attr}>")),
    }
}

/// An `<inertial>`'s mass (finite, ≥ 0) and centre of mass (`<origin xyz>`, default
/// 0; `rpy` turns only the inertia tensor), or what is malformed.
fn inertial_mass(e: roxmltree::Node) -> Result<(f64, Vector3), String> {
    let mass = inertial_number(e, "mass", "value")?;
    if !(0.0..=grasp_core::problem::MAX_MAGNITUDE).contains(&mass) {
        return Err(format!("<mass value=\"{mass}\">: expected 0 to 1e12"));
    }
    let com = match e
        .children()
        .find(|c| c.has_tag_name("origin"))
        .and_then(|c| c.attribute("xyz"))
    {
        None => Vector3::zeros(),
        Some(text) => {
            let v: Vec<f64> = text
                .split_whitespace()
                .filter_map(|v| v.parse::<f64>().ok())
                .filter(|x| x.is_finite() && x.abs() <= grasp_core::problem::MAX_MAGNITUDE)
                .collect();
            if v.len() != 3 || text.split_whitespace().count() != 3 {
                return Err(format!(
                    "<origin xyz=\"{text}\">: expected 3 finite numbers"
                ));
            }
            Vector3::new(v[0], v[1], v[2])
        }
    };
    Ok((mass, com))
}

/// The first malformed entry of an `<inertial>`'s `<inertia>`, if any.
fn malformed_tensor(e: roxmltree::Node) -> Option<String> {
    ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]
        .iter()
        .find_map(|a| inertial_number(e, "inertia", a).err())
}

impl Robot {
    /// Reads and checks a URDF file (at most [`crate::file::MAX_FILE_BYTES`]).
    /// An MJCF file (root element `<mujoco>`) is read by [`Robot::load_mjcf`].
    pub fn load(path: &Path) -> Result<Self, ProblemError> {
        let text = crate::file::read_limited(path)?;
        if is_mjcf(&text) {
            return Self::parse_mjcf(&text, &path.display().to_string(), path.parent());
        }
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses and checks URDF text; `source` names it in messages.
    pub fn parse(text: &str, source: &str) -> Result<Self, ProblemError> {
        let file = source;
        let scan = scan(text, file)?;
        let Scan {
            name,
            links,
            link_lines,
            joints: raw,
            warnings,
            masses,
        } = scan;
        let mut warnings = warnings;
        let joint_index: HashMap<&str, usize> = raw
            .iter()
            .enumerate()
            .map(|(i, j)| (j.name.as_str(), i))
            .collect();
        let joint_at = |name: &str| {
            format!(
                "<joint name=\"{name}\"> (line {})",
                joint_index.get(name).map_or(0, |&j| raw[j].line)
            )
        };
        let link_index: HashMap<&str, usize> = links
            .iter()
            .enumerate()
            .map(|(i, n)| (n.as_str(), i))
            .collect();
        if links.is_empty() {
            return Err(robot_error(file, "<robot>", "has no <link>"));
        }
        let mut joints = Vec::with_capacity(raw.len());
        let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
        let mut base_mounts: Vec<(usize, &str)> = Vec::new();
        for (ji, j) in raw.iter().enumerate() {
            let at = joint_at(&j.name);
            let find = |role: &str, name: &str| {
                link_index.get(name).copied().ok_or_else(|| {
                    robot_error(
                        file,
                        &at,
                        format!(
                            "its {role} link `{name}` is not a <link> of this robot ({})",
                            nearest(name, links.iter().map(String::as_str))
                        ),
                    )
                })
            };
            let parent = find("parent", &j.parent)?;
            let child = find("child", &j.child)?;
            if parent == child {
                return Err(robot_error(
                    file,
                    &at,
                    "its parent and child are the same link",
                ));
            }
            if let Some(other) = parent_joint[child] {
                return Err(robot_error(
                    file,
                    &at,
                    format!(
                        "link `{}` is already the child of joint `{}`: a link has one parent",
                        links[child], raw[other].name
                    ),
                ));
            }
            parent_joint[child] = Some(ji);
            let kind = match j.kind {
                "revolute" => JointKind::Revolute,
                "continuous" => JointKind::Continuous,
                "prismatic" => JointKind::Prismatic,
                "fixed" => JointKind::Fixed,
                // A floating or planar joint from the root mounts the hand: the mount
                // holds the base, so it is fixed at its origin (checked below).
                "floating" | "planar" if j.mimic.is_none() => {
                    base_mounts.push((ji, j.kind));
                    JointKind::Fixed
                }
                other => {
                    return Err(robot_error(
                        file,
                        &at,
                        format!(
                            "joint type `{other}` is not supported: a hand's joints are revolute, continuous, prismatic or fixed (a floating or planar joint is accepted only as the mount of the whole hand, from the root link)"
                        ),
                    ))
                }
            };
            let axis = if kind == JointKind::Fixed {
                Vector3::x()
            } else {
                direction(j.axis).ok_or_else(|| {
                    robot_error(
                        file,
                        &at,
                        format!(
                            "<axis xyz> is zero; a {} joint needs a direction",
                            kind.name()
                        ),
                    )
                })?
            };
            let lim = j.limit;
            // An effort of 0 (urdf-rs's default, and a common placeholder) or +inf is
            // no limit.
            let effort = lim
                .effort
                .filter(|&e| e > 0.0 && e.is_finite())
                .map(grasp_core::TorqueLimit::Symmetric);
            let range = match (lim.lower, lim.upper) {
                (Some(lo), Some(hi)) if kind != JointKind::Continuous && lo < hi => {
                    (Some(lo), Some(hi))
                }
                _ => (None, None),
            };
            let mimic = match &j.mimic {
                None => None,
                Some(m) => {
                    let leader = joint_index.get(m.joint.as_str()).copied().ok_or_else(|| {
                        robot_error(
                            file,
                            &at,
                            format!(
                                "<mimic joint=\"{}\">: no joint of that name ({})",
                                m.joint,
                                nearest(&m.joint, raw.iter().map(|k| k.name.as_str()))
                            ),
                        )
                    })?;
                    Some(Mimic {
                        leader,
                        multiplier: m.multiplier,
                        offset: m.offset,
                    })
                }
            };
            joints.push(Joint {
                name: j.name.clone(),
                kind,
                origin: j.origin,
                axis,
                parent,
                child,
                effort,
                lower: range.0,
                upper: range.1,
                mimic,
                line: j.line,
            });
        }
        // One root, and every link reached from it (no cycle).
        let roots: Vec<usize> = (0..links.len())
            .filter(|&l| parent_joint[l].is_none())
            .collect();
        let root = match roots.as_slice() {
            [r] => *r,
            [] => {
                return Err(robot_error(
                    file,
                    "<robot>",
                    "every link is some joint's child, so the joints form a cycle and there is no root link",
                ))
            }
            many => {
                let names: Vec<String> = many
                    .iter()
                    .take(5)
                    .map(|&l| format!("`{}` (line {})", links[l], link_lines[l]))
                    .collect();
                return Err(robot_error(
                    file,
                    "<robot>",
                    format!(
                        "{} root links (links that are no joint's child): {}{}; a hand is one tree",
                        many.len(),
                        names.join(", "),
                        if many.len() > 5 { ", …" } else { "" }
                    ),
                ));
            }
        };
        for (ji, kind) in base_mounts {
            let j = &joints[ji];
            if j.parent != root {
                return Err(robot_error(
                    file,
                    joint_at(&j.name),
                    format!(
                        "joint type `{kind}` is not supported inside the hand: a floating or planar joint is accepted only as the mount of the whole hand, from the root link `{}`",
                        links[root]
                    ),
                ));
            }
            warnings.push(format!(
                "{file}: {}: a {kind} joint from the root link mounts the hand; it is held fixed at its <origin>, so the object pose is relative to `{}`",
                joint_at(&j.name),
                links[root]
            ));
        }
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); links.len()];
        for (ji, j) in joints.iter().enumerate() {
            children[j.parent].push(ji);
        }
        let mut order = Vec::with_capacity(links.len());
        let mut stack = vec![root];
        while let Some(l) = stack.pop() {
            order.push(l);
            stack.extend(children[l].iter().rev().map(|&ji| joints[ji].child));
        }
        if order.len() < links.len() {
            let mut reached = vec![false; links.len()];
            for &l in &order {
                reached[l] = true;
            }
            let lost = (0..links.len()).find(|&l| !reached[l]).unwrap_or(0);
            return Err(robot_error(
                file,
                format!(
                    "<link name=\"{}\"> (line {})",
                    links[lost], link_lines[lost]
                ),
                "is on a cycle of joints: it cannot be reached from the root link",
            ));
        }
        let (independent, coupling) =
            resolve_couplings(&joints, file, &mut warnings, |n| joint_at(n))?;
        let masses = links
            .iter()
            .map(|n| masses.get(n).cloned().unwrap_or(LinkMass::None))
            .collect();
        Ok(Self {
            name,
            source: file.to_string(),
            links,
            joints,
            root,
            independent,
            coupling,
            warnings,
            parent_joint,
            order,
            link_lines,
            sites: Vec::new(),
            actuators: Vec::new(),
            tendons: Vec::new(),
            springs: Vec::new(),
            masses,
            gravity: None,
        })
    }

    /// A tree built by another reader (MJCF): link 0 is the root, every other link is
    /// one joint's child, and mimic couplings and positions are measured from each
    /// joint's `reference` (joint motion is `q − reference`).
    pub(crate) fn from_tree(
        name: String,
        source: String,
        links: Vec<String>,
        link_lines: Vec<u32>,
        joints: Vec<Joint>,
        reference: &[f64],
        mut warnings: Vec<String>,
    ) -> Result<Self, ProblemError> {
        let mut parent_joint = vec![None; links.len()];
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); links.len()];
        for (ji, j) in joints.iter().enumerate() {
            parent_joint[j.child] = Some(ji);
            children[j.parent].push(ji);
        }
        let mut order = Vec::with_capacity(links.len());
        let mut stack = vec![0];
        while let Some(l) = stack.pop() {
            order.push(l);
            stack.extend(children[l].iter().rev().map(|&ji| joints[ji].child));
        }
        let file = source.clone();
        let (independent, mut coupling) = resolve_couplings(&joints, &file, &mut warnings, |n| {
            format!(
                "<joint name=\"{n}\"> (line {})",
                joints.iter().find(|j| j.name == n).map_or(0, |j| j.line)
            )
        })?;
        // Motion is measured from each joint's reference position: q − ref.
        for c in coupling.iter_mut().flatten() {
            c.offset -= c.multiplier * reference[independent[c.independent]];
        }
        Ok(Self {
            name,
            source,
            links,
            joints,
            root: 0,
            independent,
            coupling,
            warnings,
            parent_joint,
            order,
            link_lines,
            sites: Vec::new(),
            actuators: Vec::new(),
            tendons: Vec::new(),
            springs: Vec::new(),
            masses: Vec::new(),
            gravity: None,
        })
    }

    /// The index of the link called `name`.
    pub fn link(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l == name)
    }

    /// The index of the joint called `name`.
    pub fn joint(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Line of a link's element in the file.
    pub fn link_line(&self, link: usize) -> u32 {
        self.link_lines[link]
    }

    /// The joints from the root to `link`, root first (fixed ones included).
    pub fn chain(&self, link: usize) -> Vec<usize> {
        let mut chain = Vec::new();
        let mut at = link;
        while let Some(j) = self.parent_joint[at] {
            chain.push(j);
            at = self.joints[j].parent;
        }
        chain.reverse();
        chain
    }

    /// The frame called `name`: an MJCF site's, else a link's, as the link it is on and
    /// its placement in that link's frame (the identity for a link). `field` names the
    /// caller's argument in the error, which lists the nearest names.
    pub fn named_frame(&self, name: &str, field: &str) -> Result<(usize, Isometry3), ProblemError> {
        if let Some(s) = self.sites.iter().find(|s| s.name == name) {
            return Ok((s.link, s.frame));
        }
        let link = self.link(name).ok_or_else(|| {
            let names = self.links.iter().chain(self.sites.iter().map(|s| &s.name));
            ProblemError::invalid(
                field,
                format!(
                    "a link or site of {} ({})",
                    self.source,
                    nearest(name, names.map(String::as_str))
                ),
                format!("`{name}`"),
            )
        })?;
        Ok((link, Isometry3::identity()))
    }

    /// Marks `link` and every link above it (what [`Robot::pose_of`] needs to place it).
    pub fn mark_ancestors(&self, link: usize, needed: &mut [bool]) {
        needed[link] = true;
        for j in self.chain(link) {
            needed[self.joints[j].parent] = true;
        }
    }

    /// The links no joint has as parent: the ends of the chains.
    pub fn leaves(&self) -> Vec<usize> {
        let mut has_child = vec![false; self.links.len()];
        for j in &self.joints {
            has_child[j.parent] = true;
        }
        self.order
            .iter()
            .copied()
            .filter(|&l| !has_child[l])
            .collect()
    }

    /// The position of every joint (radians or metres) from the independent
    /// coordinates; fixed joints get 0.
    pub fn full_positions(&self, q_ind: &[f64]) -> Vec<f64> {
        self.coupling
            .iter()
            .map(|c| c.map_or(0.0, |c| c.multiplier * q_ind[c.independent] + c.offset))
            .collect()
    }

    /// Frames of every link and joint at the independent coordinates `q_ind` (one per
    /// [`Robot::independent`]), in the root link's frame.
    pub fn pose(&self, q_ind: &[f64]) -> Pose {
        self.pose_where(q_ind, |_| true)
    }

    /// [`Robot::pose`] of the links marked in `needed` and the joints above them only
    /// (a marked link's parent must be marked too: the contacts' links and their
    /// ancestors); the other frames are left at the identity. A hand on an arm, or an
    /// MJCF scene, has many bodies that no contact's chain passes through.
    pub fn pose_of(&self, q_ind: &[f64], needed: &[bool]) -> Pose {
        self.pose_where(q_ind, |l| needed[l])
    }

    fn pose_where(&self, q_ind: &[f64], needed: impl Fn(usize) -> bool) -> Pose {
        self.pose_full(&self.full_positions(q_ind), needed)
    }

    /// The frames at every joint's motion `q` (one per [`Robot::joints`], couplings not
    /// applied) of the links `needed` marks.
    pub(crate) fn pose_full(&self, q: &[f64], needed: impl Fn(usize) -> bool) -> Pose {
        let mut links = vec![Isometry3::identity(); self.links.len()];
        let mut joints = vec![Isometry3::identity(); self.joints.len()];
        for &l in &self.order {
            let Some(ji) = self.parent_joint[l].filter(|_| needed(l)) else {
                continue;
            };
            let j = &self.joints[ji];
            let frame = links[j.parent] * j.origin;
            let motion = match j.kind {
                JointKind::Fixed => Isometry3::identity(),
                JointKind::Revolute | JointKind::Continuous => Isometry3::from_parts(
                    Vector3::zeros(),
                    UnitQuaternion::from_axis_angle(&j.axis, q[ji]),
                ),
                JointKind::Prismatic => {
                    Isometry3::from_parts(j.axis * q[ji], UnitQuaternion::identity())
                }
            };
            joints[ji] = frame;
            links[l] = frame * motion;
        }
        Pose { links, joints }
    }
}

/// The unit vector along `v`; `None` for the zero vector. Components too large to
/// square are scaled first.
pub(crate) fn direction(v: Vector3) -> Option<Vector3> {
    let n = v.norm();
    if n == 0.0 {
        None
    } else if n.is_finite() {
        Some(v / n)
    } else {
        let big = v.x.abs().max(v.y.abs()).max(v.z.abs());
        Some((v / big).normalize())
    }
}

/// Byte offsets of the newlines of `text`, for [`line_at`].
pub(crate) fn newline_offsets(text: &str) -> Vec<usize> {
    text.bytes()
        .enumerate()
        .filter(|&(_, b)| b == b'\n')
        .map(|(i, _)| i)
        .collect()
}

/// The 1-based line of byte `offset`, by binary search: roxmltree's `text_pos_at`
/// scans from the start, which made a 9 000-link URDF take 34 s.
pub(crate) fn line_at(newlines: &[usize], offset: usize) -> u32 {
    newlines.partition_point(|&i| i < offset) as u32 + 1
}

/// Whether the first element of an XML text is `<mujoco>` (MJCF) rather than `<robot>`.
fn is_mjcf(text: &str) -> bool {
    let mut rest = text.trim_start_matches('\u{feff}');
    loop {
        rest = rest.trim_start();
        if let Some(r) = rest.strip_prefix("<?") {
            rest = r.split_once("?>").map_or("", |x| x.1);
        } else if let Some(r) = rest.strip_prefix("<!--") {
            rest = r.split_once("-->").map_or("", |x| x.1);
        } else if let Some(r) = rest.strip_prefix("<!") {
            rest = r.split_once('>').map_or("", |x| x.1);
        } else {
            return rest.starts_with("<mujoco");
        }
    }
}

/// Mimic chains resolved to independent joints: the independent joints (neither fixed
/// nor mimic, in order) and each moving joint's coupling to one of them.
#[allow(clippy::type_complexity)]
fn resolve_couplings(
    joints: &[Joint],
    file: &str,
    warnings: &mut Vec<String>,
    joint_at: impl Fn(&str) -> String,
) -> Result<(Vec<usize>, Vec<Option<Coupling>>), ProblemError> {
    let independent: Vec<usize> = (0..joints.len())
        .filter(|&j| joints[j].kind != JointKind::Fixed && joints[j].mimic.is_none())
        .collect();
    let mut coupling: Vec<Option<Coupling>> = vec![None; joints.len()];
    for (k, &j) in independent.iter().enumerate() {
        coupling[j] = Some(Coupling {
            independent: k,
            multiplier: 1.0,
            offset: 0.0,
        });
    }
    for j in 0..joints.len() {
        if joints[j].kind == JointKind::Fixed {
            if joints[j].mimic.is_some() {
                warnings.push(format!(
                    "{file}: {}: a fixed joint with <mimic>; the mimic is ignored",
                    joint_at(&joints[j].name)
                ));
            }
            continue;
        }
        let (mut at, mut mult, mut off, mut steps) = (j, 1.0, 0.0, 0);
        while let Some(m) = joints[at].mimic {
            if joints[m.leader].kind == JointKind::Fixed {
                return Err(robot_error(
                    file,
                    joint_at(&joints[at].name),
                    format!(
                        "<mimic joint=\"{}\">: that joint is fixed",
                        joints[m.leader].name
                    ),
                ));
            }
            // q_at = m q_leader + o, so q_j = mult q_at + off = mult m q_leader + (mult o + off).
            off += mult * m.offset;
            mult *= m.multiplier;
            at = m.leader;
            steps += 1;
            if steps > joints.len() {
                return Err(robot_error(
                    file,
                    joint_at(&joints[j].name),
                    "its <mimic> chain comes back to itself (a cycle of mimic joints)",
                ));
            }
        }
        let base = coupling[at].expect("an independent joint has a coupling");
        coupling[j] = Some(Coupling {
            independent: base.independent,
            multiplier: mult,
            offset: off,
        });
    }
    Ok((independent, coupling))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_is_fixed_axis_roll_pitch_yaw() {
        let (r, p, y) = (0.3, -0.7, 1.1);
        let q = UnitQuaternion::from_euler_angles(r, p, y);
        let rx = UnitQuaternion::from_axis_angle(&Vector3::x(), r);
        let ry = UnitQuaternion::from_axis_angle(&Vector3::y(), p);
        let rz = UnitQuaternion::from_axis_angle(&Vector3::z(), y);
        assert!(q.angle_to(&(rz * ry * rx)) < 1e-15);
    }

    #[test]
    fn nearest_names() {
        assert_eq!(edit_distance("joint_0.0", "joint_0.0"), 0);
        assert_eq!(edit_distance("joint_00", "joint_0.0"), 1);
        let s = nearest("jiont_1.0", ["joint_1.0", "joint_10.0", "link_1.0", "zzz"]);
        assert!(s.starts_with("nearest: `joint_1.0`"), "{s}");
    }
}
