//! MuJoCo hands (MJCF): the kinematic tree, sites, fixed tendons, actuators and joint
//! couplings of the subset of MJCF that hand models use, read with `roxmltree`.
//!
//! - **Structure:** `<include file>` (relative to the including file, then to the main
//!   file), `<default>` classes with `class` and `childclass` inheritance, and
//!   `<compiler angle eulerseq>` (MuJoCo's defaults: degrees, `xyz`).
//! - **Frames:** a body's or site's `pos` with one of `quat`, `euler`, `axisangle`,
//!   `xyaxes` or `zaxis` (sites also `fromto`). A body's joints move it in document
//!   order, each a rotation about (hinge) or a translation along (slide) its `axis`
//!   through its `pos`, by `q − ref`, as MuJoCo's forward kinematics does. In the tree
//!   each joint is followed by a fixed joint back from its anchor, so the joints keep
//!   the URDF reader's convention (a joint frame at the anchor).
//! - **Couplings:** `<equality><joint>` with a linear `polycoef`, and `<equality><tendon>`
//!   on a fixed tendon of two joints, become mimic couplings (the later joint follows).
//! - **Actuators:** `motor`, `general`, `position`, `velocity`, `intvelocity`,
//!   `cylinder` and `plugin` on a `joint`, a fixed `tendon` (the moment arm is the gear,
//!   times the tendon's coefficients) or a spatial `tendon` (the gear times the
//!   derivative of the tendon's length, which depends on the configuration: sites,
//!   sphere and cylinder geoms wrapped as MuJoCo wraps them, pulleys; see
//!   [`crate::tendon`]). Gains and biases do not enter statics.
//!
//! A `free` joint on a body directly under `<worldbody>` with joints below it (a
//! floating hand) is held fixed, and that body's frame becomes the reference frame; a
//! free body without (an object of the scene) stays where the file puts it; `<frame>` moves the
//! bodies and sites it holds. `free` and `ball` joints inside the tree, `<composite>`,
//! `<flexcomp>`, `<replicate>`, `<attach>` and `<equality><connect>` change the
//! kinematics and are errors. Meshes, textures and assets are never opened. A geom
//! matters when a spatial tendon wraps it, and for its body's mass (`<inertial>`, or
//! the geoms' as MuJoCo's compiler computes them, [`crate::mass`]); a geom or inertial
//! that cannot be read fails only what needs it (a tendon, gravity). Other elements are
//! ignored, with one warning per element name.

use crate::frame::{Isometry3, UnitQuaternion, Vector3};
use crate::mass::LinkMass;
use crate::tendon::{PathPoint, SpatialTendon, Spring, SpringOn, WrapGeom, WrapShape};
use crate::urdf::{
    line_at, nearest, newline_offsets, Actuator, Drive, Joint, JointKind, LimitSource, Robot, Site,
    MAX_DEPTH, MAX_LINKS,
};
use grasp_core::error::ProblemError;
use grasp_core::TorqueLimit;
use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};

/// Deepest `<include>` nesting (a cycle of includes stops here).
const MAX_INCLUDE_DEPTH: usize = 16;

/// Most elements read across all files.
const MAX_ELEMENTS: usize = 1_000_000;

/// One element, with includes expanded.
#[derive(Debug)]
struct El {
    name: String,
    attrs: Vec<(String, String)>,
    children: Vec<El>,
    file: usize,
    line: u32,
}

impl El {
    fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

struct Reader {
    /// `<mujoco model>` of the main file.
    model: Option<String>,
    files: Vec<String>,
    main_dir: PathBuf,
    elements: usize,
}

fn error(file: &str, element: impl Into<String>, message: impl Into<String>) -> ProblemError {
    ProblemError::RobotModel {
        file: file.to_string(),
        element: element.into(),
        message: message.into(),
    }
}

impl Reader {
    fn at(&self, e: &El) -> String {
        format!("<{}> (line {})", e.name, e.line)
    }

    fn err(&self, e: &El, message: impl Into<String>) -> ProblemError {
        error(&self.files[e.file], self.at(e), message)
    }

    /// The children of the document's root element, includes expanded.
    fn parse(
        &mut self,
        text: &str,
        name: String,
        dir: Option<&Path>,
        depth: usize,
    ) -> Result<Vec<El>, ProblemError> {
        let file = self.files.len();
        self.files.push(name);
        let doc = roxmltree::Document::parse(text).map_err(|e| {
            error(
                &self.files[file],
                "(document)",
                format!("not well-formed XML: {e}"),
            )
        })?;
        let root = doc.root_element();
        let tag = root.tag_name().name();
        if tag != "mujoco" && tag != "mujocoinclude" {
            return Err(error(
                &self.files[file],
                format!("<{tag}>"),
                "the root element of an MJCF file is <mujoco>",
            ));
        }
        if file == 0 {
            self.model = root.attribute("model").map(str::to_string);
        }
        let newlines = newline_offsets(text);
        let mut out = Vec::new();
        for c in root.children().filter(|c| c.is_element()) {
            self.convert(&newlines, c, file, dir, depth, 1, &mut out)?;
        }
        Ok(out)
    }

    #[allow(clippy::too_many_arguments)]
    fn convert(
        &mut self,
        newlines: &[usize],
        node: roxmltree::Node,
        file: usize,
        dir: Option<&Path>,
        include_depth: usize,
        depth: usize,
        out: &mut Vec<El>,
    ) -> Result<(), ProblemError> {
        let line = line_at(newlines, node.range().start);
        let name = node.tag_name().name().to_string();
        if depth > MAX_DEPTH {
            return Err(error(
                &self.files[file],
                format!("<{name}> (line {line})"),
                format!("elements nested more than {MAX_DEPTH} deep"),
            ));
        }
        self.elements += 1;
        if self.elements > MAX_ELEMENTS {
            return Err(error(
                &self.files[file],
                format!("<{name}> (line {line})"),
                format!("more than {MAX_ELEMENTS} elements"),
            ));
        }
        if name == "include" {
            let Some(target) = node.attribute("file") else {
                return Err(error(
                    &self.files[file],
                    format!("<include> (line {line})"),
                    "has no file attribute",
                ));
            };
            if include_depth >= MAX_INCLUDE_DEPTH {
                return Err(error(
                    &self.files[file],
                    format!("<include file=\"{target}\"> (line {line})"),
                    format!("includes nested more than {MAX_INCLUDE_DEPTH} deep (a file that includes itself?)"),
                ));
            }
            let here = dir.map(|d| d.join(target));
            let path = match here {
                Some(p) if p.exists() => p,
                _ => self.main_dir.join(target),
            };
            let at = format!("<include file=\"{target}\"> (line {line})");
            let text = crate::file::read_limited(&path).map_err(|e| {
                let why = match e {
                    ProblemError::Io { path, error: io } => format!("cannot read {path}: {io}"),
                    other => format!("cannot read {}: {other}", path.display()),
                };
                error(&self.files[file], &at, why)
            })?;
            let children = self.parse(
                &text,
                path.display().to_string(),
                path.parent(),
                include_depth + 1,
            )?;
            out.extend(children);
            return Ok(());
        }
        let attrs = node
            .attributes()
            .map(|a| (a.name().to_string(), a.value().to_string()))
            .collect();
        let mut children = Vec::new();
        // Assets and visual data are never needed: not even read.
        if !matches!(
            name.as_str(),
            "asset"
                | "visual"
                | "sensor"
                | "contact"
                | "keyframe"
                | "custom"
                | "extension"
                | "statistic"
                | "size"
                | "geom"
                | "inertial"
                | "camera"
                | "light"
        ) {
            for c in node.children().filter(|c| c.is_element()) {
                self.convert(
                    newlines,
                    c,
                    file,
                    dir,
                    include_depth,
                    depth + 1,
                    &mut children,
                )?;
            }
        }
        out.push(El {
            name,
            attrs,
            children,
            file,
            line,
        });
        Ok(())
    }
}

/// `<compiler>` settings that change numbers.
#[derive(Clone, Copy)]
struct Compiler {
    degrees: bool,
    eulerseq: [u8; 3],
    /// `autolimits` (MuJoCo's default, true): a range alone makes its element limited.
    /// When false, MuJoCo refuses a range whose `limited` is left unspecified.
    autolimits: bool,
    /// `inertiafromgeom`: `Some(true)` always from geoms, `Some(false)` never, `None`
    /// (`auto`, the default) for bodies without an `<inertial>`.
    inertia_from_geom: Option<bool>,
    /// `inertiagrouprange` (default 0 5): the geom groups that give a body mass.
    group_range: (f64, f64),
    /// `boundmass` (default 0): the least mass of a body.
    boundmass: f64,
    /// `settotalmass` (default −1, off): the bodies' masses are scaled to this total.
    settotalmass: f64,
}

/// A range `(lower, upper)` that limits, or None.
type LimitedRange = Option<(f64, f64)>;

/// Attributes of one element kind per default class, with the class's parent.
#[derive(Default)]
struct Defaults {
    parent: HashMap<String, Option<String>>,
    attrs: HashMap<(String, &'static str), Vec<(String, String)>>,
}

/// The actuators statics reads: each one's moment arms on the joints are its gear
/// (times a tendon's coefficients), and its `forcerange` bounds its force (or, with a
/// fixed gain and no bias, its `ctrlrange`). A `plugin` actuator's force is the
/// plugin's (a PID controller, say): only its `forcerange` bounds it.
const ACTUATORS: [&str; 7] = [
    "motor",
    "general",
    "position",
    "velocity",
    "intvelocity",
    "cylinder",
    "plugin",
];
/// Actuators that exert no force at rest (`damper`), only pull through a length- and
/// velocity-dependent law (`muscle`), or act on contacts (`adhesion`).
const IGNORED_ACTUATORS: [&str; 3] = ["damper", "muscle", "adhesion"];

fn default_kind(name: &str) -> Option<&'static str> {
    match name {
        "joint" => Some("joint"),
        "site" => Some("site"),
        "geom" => Some("geom"),
        "tendon" => Some("tendon"),
        "equality" => Some("equality"),
        n if ACTUATORS.contains(&n) || IGNORED_ACTUATORS.contains(&n) => Some("actuator"),
        _ => None,
    }
}

impl Defaults {
    fn read(&mut self, r: &Reader, e: &El, parent: Option<&str>) -> Result<(), ProblemError> {
        let class = match (e.attr("class"), parent) {
            (Some(c), _) => c.to_string(),
            (None, None) => "main".to_string(),
            (None, Some(_)) => return Err(r.err(e, "a nested <default> needs a class attribute")),
        };
        let previous = self
            .parent
            .insert(class.clone(), parent.map(str::to_string));
        // MuJoCo refuses a repeated class name; the top level's `main` may recur across
        // included files.
        if previous.is_some() && parent.is_some() {
            return Err(r.err(e, format!("a second <default class=\"{class}\">")));
        }
        for c in &e.children {
            if c.name == "default" {
                self.read(r, c, Some(&class))?;
            } else if let Some(kind) = default_kind(&c.name) {
                let slot = self.attrs.entry((class.clone(), kind)).or_default();
                for (k, v) in &c.attrs {
                    slot.retain(|(k2, _)| k2 != k);
                    slot.push((k.clone(), v.clone()));
                }
            }
        }
        Ok(())
    }

    /// The value of `key` for an element of `kind` in `class`: its own, else the
    /// nearest class's up to `main`.
    fn lookup<'a>(
        &'a self,
        e: &'a El,
        kind: &'static str,
        class: &str,
        key: &str,
    ) -> Option<&'a str> {
        if let Some(v) = e.attr(key) {
            return Some(v);
        }
        let mut at = Some(class.to_string());
        let mut steps = 0;
        while let Some(c) = at {
            if let Some(v) = self
                .attrs
                .get(&(c.clone(), kind))
                .and_then(|a| a.iter().find(|(k, _)| k == key))
            {
                return Some(&v.1);
            }
            at = self.parent.get(&c).cloned().flatten();
            steps += 1;
            if steps > 64 {
                break;
            }
        }
        None
    }
}

/// An element's attributes through its default class.
struct View<'a> {
    r: &'a Reader,
    d: &'a Defaults,
    e: &'a El,
    kind: &'static str,
    class: String,
}

impl<'a> View<'a> {
    fn get(&self, key: &str) -> Option<&'a str> {
        self.d.lookup(self.e, self.kind, &self.class, key)
    }

    fn numbers(&self, key: &str) -> Result<Option<Vec<f64>>, ProblemError> {
        let Some(text) = self.get(key) else {
            return Ok(None);
        };
        text.split_whitespace()
            .map(|v| {
                v.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite() && x.abs() <= 1e12)
            })
            .collect::<Option<Vec<f64>>>()
            .map(Some)
            .ok_or_else(|| {
                self.r.err(
                    self.e,
                    format!("{key}=\"{text}\": expected finite numbers of magnitude at most 1e12"),
                )
            })
    }

    fn fixed<const N: usize>(&self, key: &str) -> Result<Option<[f64; N]>, ProblemError> {
        match self.numbers(key)? {
            None => Ok(None),
            Some(v) => <[f64; N]>::try_from(v.as_slice()).map(Some).map_err(|_| {
                self.r.err(
                    self.e,
                    format!("{key}: expected {N} numbers, got {}", v.len()),
                )
            }),
        }
    }

    /// The first of up to `max` numbers (MuJoCo pads such vectors with zeros).
    fn leading(&self, key: &str, max: usize) -> Result<Option<f64>, ProblemError> {
        match self.numbers(key)? {
            None => Ok(None),
            Some(v) if v.is_empty() || v.len() > max => Err(self.r.err(
                self.e,
                format!("{key}: expected 1 to {max} numbers, got {}", v.len()),
            )),
            Some(v) => Ok(Some(v[0])),
        }
    }

    fn flag(&self, key: &str) -> Result<Option<bool>, ProblemError> {
        match self.get(key) {
            None | Some("auto") => Ok(None),
            Some("true") => Ok(Some(true)),
            Some("false") => Ok(Some(false)),
            Some(v) => Err(self.r.err(
                self.e,
                format!("{key}=\"{v}\": expected true, false or auto"),
            )),
        }
    }

    /// The element's `{prefix}range` when it limits (None when it does not), by
    /// MuJoCo's rules: `{prefix}limited="true"` needs lower < upper;
    /// unspecified (or `auto`), a range with lower < upper limits when the compiler's
    /// `autolimits` is on (any other range, `0 0` included, does not), and without
    /// autolimits any range but `0 0` is an error.
    fn limits(&self, prefix: &str, autolimits: bool) -> Result<LimitedRange, ProblemError> {
        let key = format!("{prefix}range");
        let range = self.fixed::<2>(&key)?.map(|[lo, hi]| (lo, hi));
        let ordered = range.is_some_and(|(lo, hi)| lo < hi);
        let limited = match self.flag(&format!("{prefix}limited"))? {
            Some(true) if !ordered => {
                return Err(self.r.err(
                    self.e,
                    match range {
                        Some((lo, hi)) => format!("{prefix}limited=\"true\" with {key}=\"{lo} {hi}\": expected lower < upper"),
                        None => format!("{prefix}limited=\"true\" without a {key}"),
                    },
                ))
            }
            Some(l) => l,
            None if autolimits => ordered,
            None if range.is_some_and(|r| r != (0.0, 0.0)) => {
                return Err(self.r.err(
                    self.e,
                    format!("{key} is given but not {prefix}limited, and the compiler's autolimits is false (MuJoCo refuses this model): set {prefix}limited=\"true\" or \"false\", or autolimits=\"true\""),
                ))
            }
            None => false,
        };
        Ok(range.filter(|_| limited))
    }

    /// A site's or geom's frame: from `fromto` (centred between the points, the z axis
    /// along them) when given, else [`View::frame`].
    fn placement(&self, c: Compiler) -> Result<Isometry3, ProblemError> {
        let Some(ft) = self.fixed::<6>("fromto")? else {
            return self.frame(c);
        };
        let (a, b) = (
            Vector3::new(ft[0], ft[1], ft[2]),
            Vector3::new(ft[3], ft[4], ft[5]),
        );
        // MuJoCo's z axis points from `to` back to `from`; ends that coincide to
        // rounding (relative to where they are, so in any unit) leave it unrotated.
        let dir = a - b;
        let rot = if dir.norm() <= 1e-12 * a.norm().max(b.norm()) {
            UnitQuaternion::identity()
        } else {
            z_to(dir.normalize())
        };
        Ok(Isometry3::from_parts((a + b) / 2.0, rot))
    }

    /// `pos` and the orientation (at most one of quat, euler, axisangle, xyaxes, zaxis).
    fn frame(&self, c: Compiler) -> Result<Isometry3, ProblemError> {
        let pos = self.fixed::<3>("pos")?.unwrap_or([0.0; 3]);
        let given: Vec<&str> = ["quat", "euler", "axisangle", "xyaxes", "zaxis"]
            .into_iter()
            .filter(|k| self.e.attr(k).is_some())
            .collect();
        if given.len() > 1 {
            return Err(self.r.err(
                self.e,
                format!("more than one orientation: {}", given.join(", ")),
            ));
        }
        // An orientation from the element wins over one from its class.
        let key = given.first().copied().or_else(|| {
            ["quat", "euler", "axisangle", "xyaxes", "zaxis"]
                .into_iter()
                .find(|k| self.get(k).is_some())
        });
        let angle = |a: f64| if c.degrees { a.to_radians() } else { a };
        let rot = match key {
            None => UnitQuaternion::identity(),
            Some("quat") => {
                let [w, x, y, z] = self.fixed::<4>("quat")?.unwrap_or([1.0, 0.0, 0.0, 0.0]);
                if ((x * x + z * z) + (y * y + w * w)).sqrt() < 1e-10 {
                    return Err(self.r.err(self.e, "quat: a zero quaternion"));
                }
                UnitQuaternion::new_normalize(w, x, y, z)
            }
            Some("axisangle") => {
                let [x, y, z, a] = self.fixed::<4>("axisangle")?.unwrap_or_default();
                let axis = unit(self, "axisangle", [x, y, z])?;
                UnitQuaternion::from_axis_angle(&axis, angle(a))
            }
            Some("euler") => {
                let e = self.fixed::<3>("euler")?.unwrap_or_default();
                let mut q = UnitQuaternion::identity();
                for (k, &ch) in c.eulerseq.iter().enumerate() {
                    let axis = match ch.to_ascii_lowercase() {
                        b'x' => Vector3::x(),
                        b'y' => Vector3::y(),
                        _ => Vector3::z(),
                    };
                    let r = UnitQuaternion::from_axis_angle(&axis, angle(e[k]));
                    // Lower case: about the moving axes (intrinsic); upper case: fixed.
                    q = if ch.is_ascii_lowercase() {
                        q * r
                    } else {
                        r * q
                    };
                }
                q
            }
            Some("xyaxes") => {
                let v = self.fixed::<6>("xyaxes")?.unwrap_or_default();
                let x = unit(self, "xyaxes", [v[0], v[1], v[2]])?;
                let y0 = Vector3::new(v[3], v[4], v[5]);
                let y = y0 - x * x.dot(&y0);
                if y.norm() < 1e-10 {
                    return Err(self
                        .r
                        .err(self.e, "xyaxes: the y axis is parallel to the x axis"));
                }
                let y = y.normalize();
                let z = x.cross(&y);
                // The axes are the matrix's columns.
                UnitQuaternion::from_rotation_matrix(&[
                    [x.x, y.x, z.x],
                    [x.y, y.y, z.y],
                    [x.z, y.z, z.z],
                ])
            }
            Some(_) => {
                let z = unit(
                    self,
                    "zaxis",
                    self.fixed::<3>("zaxis")?.unwrap_or([0.0, 0.0, 1.0]),
                )?;
                z_to(z)
            }
        };
        Ok(Isometry3::from_parts(Vector3::from(pos), rot))
    }
}

/// The rotation that takes (0, 0, 1) to `z` by the shortest arc (π about x when `z`
/// points down), as MuJoCo's `zaxis`.
fn z_to(z: Vector3) -> UnitQuaternion {
    UnitQuaternion::rotation_between(&Vector3::z(), &z)
        .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::x(), std::f64::consts::PI))
}

fn unit(v: &View, key: &str, x: [f64; 3]) -> Result<Vector3, ProblemError> {
    let x = Vector3::from(x);
    if x.norm() < 1e-10 {
        return Err(v.r.err(v.e, format!("{key}: a zero axis")));
    }
    Ok(x.normalize())
}

/// The tree being built.
struct Tree {
    links: Vec<String>,
    link_lines: Vec<u32>,
    body_link: HashMap<String, usize>,
    joints: Vec<Joint>,
    reference: Vec<f64>,
    sites: Vec<Site>,
    /// Named geoms: what a spatial tendon can wrap, or why it cannot (read only when
    /// a tendon names it, so that no other geom can fail the model).
    geoms: HashMap<String, Result<WrapGeom, ProblemError>>,
    warnings: Vec<String>,
    ignored: BTreeSet<String>,
    /// The floating hand's body, held fixed at the reference frame.
    mount: Option<String>,
    /// Per joint with a `springref`, its value (radians for a hinge); 0 elsewhere.
    springref: HashMap<usize, f64>,
    /// Joints with a spring: (joint, stiffness).
    joint_springs: Vec<(usize, f64)>,
    /// The bodies, for their masses.
    bodies: Vec<Body>,
    /// Each geom on a body: its link and what it weighs (`None`: outside the
    /// compiler's `inertiagrouprange`).
    geom_masses: Vec<(usize, Option<PointMass>)>,
}

/// A mass (kg) at a point of its link's frame, or why it is not known.
type PointMass = Result<(f64, Vector3), String>;

/// What a body's mass is computed from.
struct Body {
    link: usize,
    /// Its `<inertial>`'s mass and centre, if it has one.
    inertial: Option<PointMass>,
    gravcomp: f64,
    /// Its `pos` attribute.
    pos: Vector3,
}

impl Tree {
    fn add_link(&mut self, name: String, line: u32) -> usize {
        self.links.push(name);
        self.link_lines.push(line);
        self.links.len() - 1
    }

    #[allow(clippy::too_many_arguments)]
    fn add_joint(
        &mut self,
        name: String,
        kind: JointKind,
        origin: Isometry3,
        axis: Vector3,
        parent: usize,
        child: usize,
        range: Option<(f64, f64)>,
        reference: f64,
        effort: Option<TorqueLimit>,
        line: u32,
    ) {
        self.joints.push(Joint {
            name,
            kind,
            origin,
            axis,
            parent,
            child,
            effort,
            lower: range.map(|r| r.0),
            upper: range.map(|r| r.1),
            mimic: None,
            line,
        });
        self.reference.push(reference);
    }
}

/// Whether a `<joint>` other than a free one sits in `body` or below it.
fn moves_below(body: &El) -> bool {
    body.children.iter().any(|c| match c.name.as_str() {
        "joint" => c.attr("type") != Some("free"),
        "body" | "frame" => moves_below(c),
        _ => false,
    })
}

/// Refuses a `class` or `childclass` that names no `<default>` class, as MuJoCo does:
/// the element would otherwise silently take another class's values.
fn check_classes(r: &Reader, d: &Defaults, elements: &[El]) -> Result<(), ProblemError> {
    for e in elements.iter().filter(|e| e.name != "default") {
        for key in ["class", "childclass"] {
            if let Some(c) = e.attr(key).filter(|c| !d.parent.contains_key(*c)) {
                let names = nearest(c, d.parent.keys().map(String::as_str));
                return Err(r.err(
                    e,
                    format!("{key}=\"{c}\": expected a <default> class of this model ({names})"),
                ));
            }
        }
        check_classes(r, d, &e.children)?;
    }
    Ok(())
}

struct Ctx<'a> {
    r: &'a Reader,
    d: &'a Defaults,
    c: Compiler,
}

impl Ctx<'_> {
    fn view<'b>(&'b self, e: &'b El, kind: &'static str, childclass: &str) -> View<'b> {
        View {
            r: self.r,
            d: self.d,
            e,
            kind,
            class: e.attr("class").unwrap_or(childclass).to_string(),
        }
    }

    /// A body under `parent`, whose frame is `offset · (pos, orientation)` (`offset`
    /// from enclosing `<frame>` elements).
    #[allow(clippy::too_many_arguments)]
    fn body(
        &self,
        t: &mut Tree,
        e: &El,
        parent: usize,
        childclass: &str,
        offset: Isometry3,
        top: bool,
    ) -> Result<(), ProblemError> {
        if t.links.len() >= MAX_LINKS {
            return Err(self
                .r
                .err(e, format!("more than {MAX_LINKS} bodies and joints")));
        }
        let v = self.view(e, "body", childclass);
        let name = e
            .attr("name")
            .map_or_else(|| format!("body at line {}", e.line), str::to_string);
        let inner = e.attr("childclass").unwrap_or(childclass).to_string();
        let mut local = offset * v.frame(self.c)?;
        let joints: Vec<&El> = e
            .children
            .iter()
            .filter(|c| c.name == "joint" || c.name == "freejoint")
            .collect();
        let mut moving = Vec::new();
        for j in &joints {
            let jv = self.view(j, "joint", &inner);
            let kind = if j.name == "freejoint" {
                "free"
            } else {
                jv.get("type").unwrap_or("hinge")
            };
            match kind {
                "hinge" | "slide" => moving.push((*j, kind == "hinge")),
                // A free body with joints below it is a floating hand, mounted at the
                // reference frame; one without is an object of the scene (Menagerie's
                // scene files hold one), which moves nothing of the hand.
                "free" if top && moves_below(e) => {
                    if let Some(first) = &t.mount {
                        return Err(self.r.err(
                            j,
                            format!("a second floating hand (`{name}`, after `{first}`): only one free body with joints can be held fixed as the reference frame; fix the other hand in the file"),
                        ));
                    }
                    t.mount = Some(name.clone());
                    t.warnings.push(format!(
                        "{}: {}: the free joint of `{name}` is held fixed; that body's frame is the reference frame of object_pose",
                        self.r.files[j.file],
                        self.r.at(j)
                    ));
                    local = Isometry3::identity();
                }
                "free" if top => t.warnings.push(format!(
                    "{}: {}: `{name}` is a free body that no joint below it moves (an object of the scene?): held where the file puts it; it is not part of the hand",
                    self.r.files[j.file],
                    self.r.at(j)
                )),
                "free" | "ball" => {
                    return Err(self.r.err(
                        j,
                        format!("a {kind} joint inside the hand (body `{name}`) is not supported: only hinge and slide joints, and a free joint on a body directly under <worldbody>"),
                    ))
                }
                other => return Err(self.r.err(j, format!("unknown joint type `{other}` (hinge, slide, ball or free)"))),
            }
        }
        // Each joint moves the body about its anchor: T(p) R T(−p), in order.
        let mut at = parent;
        let mut origin = local;
        for (k, (j, hinge)) in moving.iter().enumerate() {
            let jv = self.view(j, "joint", &inner);
            let jname = j
                .attr("name")
                .map_or_else(|| format!("{name} joint {k}"), str::to_string);
            let pos = Vector3::from(jv.fixed::<3>("pos")?.unwrap_or([0.0; 3]));
            let axis = unit(
                &jv,
                "axis",
                jv.fixed::<3>("axis")?.unwrap_or([0.0, 0.0, 1.0]),
            )?;
            let to_rad = |x: f64| {
                if *hinge && self.c.degrees {
                    x.to_radians()
                } else {
                    x
                }
            };
            let reference = to_rad(jv.leading("ref", 1)?.unwrap_or(0.0));
            // A spring: MuJoCo's qfrc_spring = −k (q − springref).
            let index = t.joints.len();
            let springref = to_rad(jv.leading("springref", 1)?.unwrap_or(0.0));
            if springref != 0.0 {
                t.springref.insert(index, springref);
            }
            if let Some(k) = jv.leading("stiffness", 3)?.filter(|&k| k != 0.0) {
                t.joint_springs.push((index, k));
            }
            if jv
                .numbers("springdamper")?
                .is_some_and(|v| v.iter().any(|&x| x != 0.0))
            {
                t.warnings.push(format!(
                    "{}: {}: springdamper (a stiffness from the body's mass) is not read: no spring on this joint",
                    self.r.files[j.file],
                    self.r.at(j)
                ));
            }
            let range = jv
                .limits("", self.c.autolimits)?
                .map(|(a, b)| (to_rad(a), to_rad(b)));
            // (A force or torque: never in degrees.)
            let effort = jv
                .limits("actuatorfrc", self.c.autolimits)?
                .map(|(lo, hi)| TorqueLimit::from_range(lo, hi));
            let child = t.add_link(format!("{name}/{jname}"), j.line);
            t.add_joint(
                jname,
                if *hinge {
                    JointKind::Revolute
                } else {
                    JointKind::Prismatic
                },
                origin * Isometry3::from_parts(pos, UnitQuaternion::identity()),
                axis,
                at,
                child,
                range,
                reference,
                effort,
                j.line,
            );
            at = child;
            origin = Isometry3::from_parts(-pos, UnitQuaternion::identity());
        }
        let link = t.add_link(name.clone(), e.line);
        if t.body_link.insert(name.clone(), link).is_some() && e.attr("name").is_some() {
            return Err(self.r.err(e, format!("a second body named `{name}`")));
        }
        t.add_joint(
            format!("{name} (fixed)"),
            JointKind::Fixed,
            origin,
            Vector3::z(),
            at,
            link,
            None,
            0.0,
            None,
            e.line,
        );
        let inertial = e.children.iter().find(|c| c.name == "inertial").map(|i| {
            let iv = self.view(i, "inertial", &inner);
            let at = |m: ProblemError| m.to_string();
            match (iv.leading("mass", 1).map_err(at)?, iv.fixed::<3>("pos").map_err(at)?) {
                (Some(m), Some(p)) if m >= 0.0 => Ok((m, Vector3::from(p))),
                (m, p) => Err(format!(
                    "<inertial> (line {}): expected a mass ≥ 0 and a pos, got mass {m:?} and pos {p:?}",
                    i.line
                )),
            }
        });
        let gravcomp = v.leading("gravcomp", 1)?.unwrap_or(0.0);
        t.bodies.push(Body {
            link,
            inertial,
            gravcomp,
            pos: Vector3::from(v.fixed::<3>("pos")?.unwrap_or([0.0; 3])),
        });
        self.children(t, e, link, &inner, Isometry3::identity(), false)
    }

    /// A named geom as a tendon would wrap it: a sphere or a cylinder, its frame on
    /// `link` and its radius.
    fn wrap_geom(
        &self,
        e: &El,
        name: &str,
        link: usize,
        childclass: &str,
        offset: Isometry3,
    ) -> Result<WrapGeom, ProblemError> {
        let v = self.view(e, "geom", childclass);
        let shape = match v.get("type").unwrap_or("sphere") {
            "sphere" => WrapShape::Sphere,
            "cylinder" => WrapShape::Cylinder,
            other => {
                return Err(self.r.err(
                    e,
                    format!(
                        "geom `{name}` of type {other}: a tendon wraps spheres and cylinders only"
                    ),
                ))
            }
        };
        let radius = v.leading("size", 3)?.unwrap_or(0.0);
        if radius <= 0.0 {
            return Err(self.r.err(
                e,
                format!("geom `{name}`: a wrapping geom needs a radius size > 0"),
            ));
        }
        Ok(WrapGeom {
            name: name.to_string(),
            link,
            frame: offset * v.placement(self.c)?,
            radius,
            shape,
        })
    }

    /// What a geom weighs and where, in its body's frame, as MuJoCo's compiler
    /// computes it for a body's inertia: its `mass`, else `density` (default 1000)
    /// times its volume, at its centre; `Ok(None)` outside `inertiagrouprange`. A mesh
    /// (whose volume and centre come from the mesh file, never read) and a shell
    /// inertia are `Err`, which matters only when gravity is asked for.
    fn geom_mass(
        &self,
        e: &El,
        childclass: &str,
        offset: Isometry3,
    ) -> Result<Option<PointMass>, String> {
        let v = self.view(e, "geom", childclass);
        let at = |m: ProblemError| m.to_string();
        let group = v.leading("group", 1).map_err(at)?.unwrap_or(0.0);
        if group < self.c.group_range.0 || group > self.c.group_range.1 {
            return Ok(None);
        }
        let kind = v.get("type").unwrap_or("sphere");
        let here = format!("geom of type {kind} (line {})", e.line);
        if v.get("shellinertia") == Some("true") {
            return Err(format!(
                "{here}: a shell inertia is not computed; give the body an <inertial>"
            ));
        }
        let size = v.numbers("size").map_err(at)?.unwrap_or_default();
        let s = |i: usize| size.get(i).copied().unwrap_or(0.0);
        let fromto = v.fixed::<6>("fromto").map_err(at)?;
        // With fromto, the half-length along the segment replaces a size.
        let half = |given: f64| {
            fromto.map_or(given, |f| {
                (Vector3::new(f[0], f[1], f[2]) - Vector3::new(f[3], f[4], f[5])).norm() / 2.0
            })
        };
        use std::f64::consts::PI;
        let volume = match kind {
            "sphere" if fromto.is_none() => 4.0 / 3.0 * PI * s(0).powi(3),
            "capsule" => PI * s(0).powi(2) * 2.0 * half(s(1)) + 4.0 / 3.0 * PI * s(0).powi(3),
            "cylinder" => PI * s(0).powi(2) * 2.0 * half(s(1)),
            // With fromto, MuJoCo takes both cross-section half-sizes from size[0].
            "ellipsoid" | "box" => {
                let s1 = if fromto.is_some() { s(0) } else { s(1) };
                let v = s(0) * s1 * half(s(2));
                if kind == "box" {
                    8.0 * v
                } else {
                    4.0 / 3.0 * PI * v
                }
            }
            "mesh" | "sdf" => {
                return Err(format!("{here}: its mass and centre come from the mesh, which is not read; give the body an <inertial>"))
            }
            other => return Err(format!("{here}: no volume for a {other} geom here; give the body an <inertial>")),
        };
        let mass = match v.leading("mass", 1).map_err(at)? {
            Some(m) => m,
            None => v.leading("density", 1).map_err(at)?.unwrap_or(1000.0) * volume,
        };
        if mass < 0.0 {
            return Err(format!("{here}: a negative mass ({mass})"));
        }
        let centre = (offset * v.placement(self.c).map_err(at)?).translation;
        Ok(Some(Ok((mass, centre))))
    }

    /// The bodies, sites and frames in `e` (a body, `<worldbody>` or `<frame>`), on
    /// `link`, moved by `offset`.
    fn children(
        &self,
        t: &mut Tree,
        e: &El,
        link: usize,
        childclass: &str,
        offset: Isometry3,
        top: bool,
    ) -> Result<(), ProblemError> {
        for c in &e.children {
            match c.name.as_str() {
                "body" => self.body(t, c, link, childclass, offset, top)?,
                "geom" => {
                    if let Some(name) = c.attr("name") {
                        let geom = self.wrap_geom(c, name, link, childclass, offset);
                        t.geoms.insert(name.to_string(), geom);
                    }
                    if !top {
                        let m = self.geom_mass(c, childclass, offset);
                        t.geom_masses
                            .push((link, m.unwrap_or_else(|e| Some(Err(e)))));
                    }
                }
                "joint" | "freejoint" | "inertial" | "camera" | "light" => {}
                "frame" => {
                    // A frame moves what it holds and may set their class.
                    let fv = self.view(c, "frame", childclass);
                    let inner = c.attr("childclass").unwrap_or(childclass);
                    self.children(t, c, link, inner, offset * fv.frame(self.c)?, top)?;
                }
                "site" => {
                    let sv = self.view(c, "site", childclass);
                    let frame = sv.placement(self.c)?;
                    t.sites.push(Site {
                        name: c
                            .attr("name")
                            .map_or_else(|| format!("site at line {}", c.line), str::to_string),
                        link,
                        frame: offset * frame,
                        line: c.line,
                    });
                }
                "composite" | "flexcomp" | "replicate" | "attach" => {
                    return Err(self
                        .r
                        .err(c, "changes the kinematic tree and is not supported here"))
                }
                other => {
                    t.ignored.insert(other.to_string());
                }
            }
        }
        Ok(())
    }
}

/// Each link's mass as MuJoCo's compiler gives it: a body's `<inertial>`, or its
/// geoms' (`inertiafromgeom`), at least `boundmass`, all scaled to `settotalmass`, and
/// then times `1 − gravcomp` (the part gravity loads).
fn body_masses(
    bodies: &[Body],
    geoms: &[(usize, Option<PointMass>)],
    c: Compiler,
    links: usize,
) -> Vec<LinkMass> {
    let mut out = vec![LinkMass::None; links];
    // Per link, its geoms in the groups.
    let mut on: Vec<Vec<&PointMass>> = vec![Vec::new(); links];
    for (l, g) in geoms {
        if let Some(g) = g {
            on[*l].push(g);
        }
    }
    let mut known = Vec::with_capacity(bodies.len());
    for b in bodies {
        // Nothing gives the body mass: MuJoCo puts its inertial frame (where
        // `boundmass` sits) at the body's `pos` attribute, read in the body's own
        // frame (MuJoCo 3.3's compiled `body_ipos`).
        let nothing = Ok((0.0, b.pos));
        let has_geoms = !on[b.link].is_empty();
        let from_geoms = || -> PointMass {
            if !has_geoms {
                return nothing.clone();
            }
            let (mut m, mut first) = (0.0, Vector3::zeros());
            for g in &on[b.link] {
                let (gm, at) = (*g).clone()?;
                m += gm;
                first += gm * at;
            }
            Ok((m, if m > 0.0 { first / m } else { Vector3::zeros() }))
        };
        // `true` prefers the geoms over an <inertial>, which still serves a body
        // without geoms in the groups.
        let mass = match (c.inertia_from_geom, &b.inertial) {
            (Some(true), Some(i)) if !has_geoms => i.clone(),
            (Some(true), _) | (None, None) => from_geoms(),
            (_, Some(i)) => i.clone(),
            (Some(false), None) => nothing.clone(),
        };
        known.push(mass.map(|(m, at)| (m.max(c.boundmass), at)));
    }
    let mut scale = 1.0;
    if c.settotalmass > 0.0 {
        match known
            .iter()
            .map(|m| m.as_ref().map(|m| m.0))
            .sum::<Result<f64, _>>()
        {
            Ok(total) if total > 0.0 => scale = c.settotalmass / total,
            Ok(_) => {}
            Err(why) => {
                let why =
                    format!("settotalmass scales every body's mass, and one is not known: {why}");
                for b in bodies {
                    out[b.link] = LinkMass::Unknown(why.clone());
                }
                return out;
            }
        }
    }
    for (b, mass) in bodies.iter().zip(known) {
        out[b.link] = match mass {
            Ok((0.0, _)) => LinkMass::None,
            Ok((m, com)) => LinkMass::Known {
                mass: m * scale * (1.0 - b.gravcomp),
                com,
            },
            Err(why) => LinkMass::Unknown(why),
        };
    }
    out
}

/// A spatial tendon's path: its sites, the named sphere and cylinder geoms it wraps
/// (each between two sites, with an optional `sidesite`) and its pulleys (each
/// starting a branch that begins with a site). Every branch ends at a site.
fn spatial_path(
    r: &Reader,
    d: &Defaults,
    e: &El,
    name: &str,
    sites: &HashMap<&str, usize>,
    geoms: &HashMap<String, Result<WrapGeom, ProblemError>>,
) -> Result<Vec<PathPoint>, ProblemError> {
    let site = |p: &El, key: &str| -> Result<usize, ProblemError> {
        let s = p
            .attr(key)
            .ok_or_else(|| r.err(p, format!("has no {key} attribute")))?;
        sites.get(s).copied().ok_or_else(|| {
            r.err(
                p,
                format!(
                    "{key} `{s}` is not a site of this model ({})",
                    nearest(s, sites.keys().copied())
                ),
            )
        })
    };
    let mut path = Vec::new();
    for p in &e.children {
        let point = match p.name.as_str() {
            "site" => PathPoint::Site(site(p, "site")?),
            "geom" => {
                let g = p
                    .attr("geom")
                    .ok_or_else(|| r.err(p, "has no geom attribute"))?;
                let geom = match geoms.get(g) {
                    Some(Ok(geom)) => geom.clone(),
                    Some(Err(why)) => {
                        return Err(r.err(p, format!("tendon `{name}` wraps geom `{g}`: {why}")))
                    }
                    None => {
                        return Err(
                            r.err(p, format!("geom `{g}` is not a named geom of this model"))
                        )
                    }
                };
                let side = p
                    .attr("sidesite")
                    .map(|_| site(p, "sidesite"))
                    .transpose()?;
                PathPoint::Wrap { geom, side }
            }
            "pulley" => {
                let v = View {
                    r,
                    d,
                    e: p,
                    kind: "tendon-pulley",
                    class: String::new(),
                };
                let divisor = v.leading("divisor", 1)?.unwrap_or(0.0);
                if divisor <= 0.0 {
                    return Err(r.err(p, "a pulley needs a divisor > 0"));
                }
                PathPoint::Pulley { divisor }
            }
            _ => continue,
        };
        path.push(point);
    }
    // Branch by branch (pulleys separate them): a site, then sites or a geom followed
    // by a site, as MuJoCo requires.
    for branch in path.split(|p| matches!(p, PathPoint::Pulley { .. })) {
        let sites = branch
            .iter()
            .filter(|p| matches!(p, PathPoint::Site(_)))
            .count();
        let well_formed = sites >= 2
            && matches!(branch.first(), Some(PathPoint::Site(_)))
            && matches!(branch.last(), Some(PathPoint::Site(_)))
            && branch.windows(2).all(|w| {
                !matches!(
                    (&w[0], &w[1]),
                    (PathPoint::Wrap { .. }, PathPoint::Wrap { .. })
                )
            });
        if !well_formed {
            return Err(r.err(
                e,
                format!("tendon `{name}`: each branch of a spatial tendon's path must start and end at a site, with at least two sites, and a geom between two sites"),
            ));
        }
    }
    Ok(path)
}

impl Robot {
    /// Reads an MJCF file and the files it includes.
    pub fn load_mjcf(path: &Path) -> Result<Self, ProblemError> {
        let text = crate::file::read_limited(path)?;
        Self::parse_mjcf(&text, &path.display().to_string(), path.parent())
    }

    /// Parses MJCF text; `source` names it in messages, includes are found relative to
    /// `dir` (the file's folder).
    pub fn parse_mjcf(text: &str, source: &str, dir: Option<&Path>) -> Result<Self, ProblemError> {
        let mut r = Reader {
            model: None,
            files: Vec::new(),
            main_dir: dir.map(Path::to_path_buf).unwrap_or_default(),
            elements: 0,
        };
        let top = r.parse(text, source.to_string(), dir, 0)?;
        let mut c = Compiler {
            degrees: true,
            eulerseq: *b"xyz",
            autolimits: true,
            inertia_from_geom: None,
            group_range: (0.0, 5.0),
            boundmass: 0.0,
            settotalmass: -1.0,
        };
        let mut gravity = Vector3::new(0.0, 0.0, -9.81);
        let mut d = Defaults::default();
        d.parent.insert("main".into(), None);
        let mut ignored = BTreeSet::new();
        for e in &top {
            match e.name.as_str() {
                "compiler" => {
                    match e.attr("angle") {
                        None => {}
                        Some("degree") => c.degrees = true,
                        Some("radian") => c.degrees = false,
                        Some(v) => {
                            return Err(
                                r.err(e, format!("angle=\"{v}\": expected degree or radian"))
                            )
                        }
                    }
                    if let Some(seq) = e.attr("eulerseq") {
                        let b = seq.as_bytes();
                        if b.len() != 3 || !b.iter().all(|ch| b"xyzXYZ".contains(ch)) {
                            return Err(r.err(
                                e,
                                format!("eulerseq=\"{seq}\": expected three of x, y, z, X, Y, Z"),
                            ));
                        }
                        c.eulerseq.copy_from_slice(b);
                    }
                    match e.attr("autolimits") {
                        None | Some("true") => c.autolimits = true,
                        Some("false") => c.autolimits = false,
                        Some(v) => {
                            return Err(
                                r.err(e, format!("autolimits=\"{v}\": expected true or false"))
                            )
                        }
                    }
                    let v = View {
                        r: &r,
                        d: &d,
                        e,
                        kind: "compiler",
                        class: String::new(),
                    };
                    c.inertia_from_geom = v.flag("inertiafromgeom")?;
                    if let Some([lo, hi]) = v.fixed::<2>("inertiagrouprange")? {
                        c.group_range = (lo, hi);
                    }
                    c.boundmass = v.leading("boundmass", 1)?.unwrap_or(c.boundmass);
                    c.settotalmass = v.leading("settotalmass", 1)?.unwrap_or(c.settotalmass);
                    if e.attr("coordinate").is_some_and(|v| v != "local") {
                        return Err(r.err(
                            e,
                            "coordinate=\"global\" is not supported (MuJoCo 3 removed it)",
                        ));
                    }
                }
                "default" => d.read(&r, e, None)?,
                "worldbody" | "tendon" | "actuator" | "equality" => {}
                "option" => {
                    let v = View {
                        r: &r,
                        d: &d,
                        e,
                        kind: "option",
                        class: String::new(),
                    };
                    if let Some(g) = v.fixed::<3>("gravity")? {
                        gravity = Vector3::from(g);
                    }
                    // `<flag gravity="disable"/>` turns it off.
                    if e.children
                        .iter()
                        .any(|f| f.name == "flag" && f.attr("gravity") == Some("disable"))
                    {
                        gravity = Vector3::zeros();
                    }
                }
                "asset" | "visual" | "sensor" | "contact" | "keyframe" | "custom" | "extension"
                | "statistic" | "size" => {}
                other => {
                    ignored.insert(other.to_string());
                }
            }
        }
        check_classes(&r, &d, &top)?;
        let ctx = Ctx { r: &r, d: &d, c };
        let mut t = Tree {
            links: Vec::new(),
            link_lines: Vec::new(),
            body_link: HashMap::new(),
            joints: Vec::new(),
            reference: Vec::new(),
            sites: Vec::new(),
            geoms: HashMap::new(),
            warnings: Vec::new(),
            ignored,
            mount: None,
            springref: HashMap::new(),
            joint_springs: Vec::new(),
            bodies: Vec::new(),
            geom_masses: Vec::new(),
        };
        let world = t.add_link("world".into(), 0);
        t.body_link.insert("world".into(), world);
        for wb in top.iter().filter(|e| e.name == "worldbody") {
            ctx.children(&mut t, wb, world, "main", Isometry3::identity(), true)?;
        }
        let joint_index: HashMap<String, usize> = t
            .joints
            .iter()
            .enumerate()
            .filter(|(_, j)| j.kind != JointKind::Fixed)
            .map(|(i, j)| (j.name.clone(), i))
            .collect();
        let moving: Vec<String> = t
            .joints
            .iter()
            .filter(|j| j.kind != JointKind::Fixed)
            .map(|j| j.name.clone())
            .collect();
        let find_joint = |e: &El, name: &str| -> Result<usize, ProblemError> {
            joint_index.get(name).copied().ok_or_else(|| {
                r.err(
                    e,
                    format!(
                        "joint `{name}` is not a hinge or slide joint of this model ({})",
                        nearest(name, moving.iter().map(String::as_str))
                    ),
                )
            })
        };
        // Fixed tendons: name → (joint, coefficient). Spatial tendons: name → index
        // of `spatial_tendons`, or why the tendon cannot be used (an error only when an
        // actuator pulls on it).
        let mut tendons: HashMap<String, Vec<(usize, f64)>> = HashMap::new();
        let mut spatial: HashMap<String, Result<usize, ProblemError>> = HashMap::new();
        let mut spatial_tendons = Vec::new();
        let site_index: HashMap<&str, usize> = t
            .sites
            .iter()
            .enumerate()
            .map(|(i, s)| (s.name.as_str(), i))
            .collect();
        let mut springs = Vec::new();
        for te in top.iter().filter(|e| e.name == "tendon") {
            for e in &te.children {
                let Some(name) = e.attr("name") else { continue };
                let v = View {
                    r: &r,
                    d: &d,
                    e,
                    kind: "tendon",
                    class: e.attr("class").unwrap_or("main").to_string(),
                };
                if let Some(k) = v.leading("stiffness", 3)?.filter(|&k| k != 0.0) {
                    let rest = match v.numbers("springlength")?.as_deref() {
                        None => None,
                        Some([l]) | Some([l, -1.0]) if *l == -1.0 => None,
                        Some([l]) => Some((*l, *l)),
                        Some([lo, hi]) if lo <= hi => Some((*lo, *hi)),
                        Some(other) => {
                            return Err(r.err(
                                e,
                                format!("springlength: expected one length or a range low ≤ high, got {other:?}"),
                            ))
                        }
                    };
                    springs.push((name.to_string(), e, k, rest));
                }
                // MuJoCo clamps the total actuator force on the tendon: not read.
                if v.limits("actuatorfrc", c.autolimits)?.is_some() {
                    t.warnings.push(format!(
                        "{}: {}: tendon `{name}`'s actuatorfrcrange is not read: the actuators on it are limited by their own ranges only",
                        r.files[e.file],
                        r.at(e)
                    ));
                }
                match e.name.as_str() {
                    "fixed" => {
                        let mut terms = Vec::new();
                        for j in e.children.iter().filter(|j| j.name == "joint") {
                            let jn = j
                                .attr("joint")
                                .ok_or_else(|| r.err(j, "has no joint attribute"))?;
                            let v = View {
                                r: &r,
                                d: &d,
                                e: j,
                                kind: "tendon-joint",
                                class: String::new(),
                            };
                            let coef = v.leading("coef", 1)?.unwrap_or(1.0);
                            terms.push((find_joint(j, jn)?, coef));
                        }
                        tendons.insert(name.to_string(), terms);
                    }
                    "spatial" => {
                        let tendon =
                            spatial_path(&r, &d, e, name, &site_index, &t.geoms).map(|path| {
                                spatial_tendons.push(SpatialTendon {
                                    name: name.to_string(),
                                    path,
                                    line: e.line,
                                });
                                spatial_tendons.len() - 1
                            });
                        spatial.insert(name.to_string(), tendon);
                    }
                    other => {
                        t.ignored.insert(format!("tendon/{other}"));
                    }
                }
            }
        }
        // Couplings from equalities.
        for eqs in top.iter().filter(|e| e.name == "equality") {
            for e in &eqs.children {
                let v = View {
                    r: &r,
                    d: &d,
                    e,
                    kind: "equality",
                    class: e.attr("class").unwrap_or("main").to_string(),
                };
                if v.get("active") == Some("false") {
                    continue;
                }
                let poly = v
                    .numbers("polycoef")?
                    .unwrap_or_else(|| vec![0.0, 1.0, 0.0, 0.0, 0.0]);
                if poly.len() > 5 || poly.iter().skip(2).any(|&x| x != 0.0) {
                    return Err(r.err(
                        e,
                        "polycoef: only a linear coupling (a0 a1 0 0 0) is supported",
                    ));
                }
                let a0 = poly.first().copied().unwrap_or(0.0);
                let a1 = poly.get(1).copied().unwrap_or(1.0);
                // (follower, leader, multiplier, offset) in motion coordinates q − ref.
                let (follower, leader, mult, off) = match e.name.as_str() {
                    "joint" => {
                        let j1 = find_joint(
                            e,
                            e.attr("joint1").ok_or_else(|| r.err(e, "has no joint1"))?,
                        )?;
                        let Some(j2) = e.attr("joint2") else {
                            return Err(r.err(
                                e,
                                "a joint equality without joint2 locks the joint; not supported",
                            ));
                        };
                        (j1, find_joint(e, j2)?, a1, a0)
                    }
                    "tendon" => {
                        if e.attr("tendon2").is_some() {
                            return Err(r.err(e, "a coupling of two tendons is not supported; one fixed tendon of two joints is"));
                        }
                        let name = e
                            .attr("tendon1")
                            .ok_or_else(|| r.err(e, "has no tendon1"))?;
                        let terms = tendons.get(name).ok_or_else(|| {
                            r.err(
                                e,
                                format!("tendon1 `{name}` is not a fixed tendon of this model"),
                            )
                        })?;
                        match terms.as_slice() {
                            // c1 m1 + c2 m2 = a0: the later joint follows.
                            [(j1, c1), (j2, c2)] if *c1 != 0.0 && *c2 != 0.0 && j1 != j2 => {
                                let ((ja, ca), (jb, cb)) = if j1 < j2 { ((*j1, *c1), (*j2, *c2)) } else { ((*j2, *c2), (*j1, *c1)) };
                                (jb, ja, -ca / cb, a0 / cb)
                            }
                            _ => return Err(r.err(e, format!("tendon `{name}` couples {} joints; a rigid tendon coupling is supported between exactly two", terms.len()))),
                        }
                    }
                    "connect" | "weld" | "distance" | "flex" => {
                        return Err(r.err(
                            e,
                            "a loop-closing equality changes the kinematics and is not supported",
                        ))
                    }
                    other => {
                        t.ignored.insert(format!("equality/{other}"));
                        continue;
                    }
                };
                if follower == leader {
                    return Err(r.err(e, "couples a joint to itself"));
                }
                if t.joints[follower].mimic.is_some() {
                    return Err(r.err(e, format!("joint `{}` is already coupled by another equality; one coupling per joint is supported", t.joints[follower].name)));
                }
                t.joints[follower].mimic = Some(crate::urdf::Mimic {
                    leader,
                    multiplier: mult,
                    offset: off,
                });
            }
        }
        // Actuators.
        let mut actuators = Vec::new();
        for group in top.iter().filter(|e| e.name == "actuator") {
            for e in &group.children {
                if !ACTUATORS.contains(&e.name.as_str()) {
                    t.ignored.insert(format!("actuator/{}", e.name));
                    continue;
                }
                let v = View {
                    r: &r,
                    d: &d,
                    e,
                    kind: "actuator",
                    class: e.attr("class").unwrap_or("main").to_string(),
                };
                let name = e
                    .attr("name")
                    .map_or_else(|| format!("{} at line {}", e.name, e.line), str::to_string);
                let gear = v.leading("gear", 6)?.unwrap_or(1.0);
                let drive = if let Some(j) = v.get("joint").or_else(|| v.get("jointinparent")) {
                    Drive::Fixed(vec![(find_joint(e, j)?, gear)])
                } else if let Some(tn) = v.get("tendon") {
                    match (tendons.get(tn), spatial.get(tn)) {
                        (Some(terms), _) => {
                            Drive::Fixed(terms.iter().map(|&(j, c)| (j, gear * c)).collect())
                        }
                        (None, Some(Ok(tendon))) => Drive::Tendon {
                            tendon: *tendon,
                            gear,
                        },
                        (None, Some(Err(why))) => {
                            return Err(r.err(
                                e,
                                format!("pulls on tendon `{tn}`, which cannot be used: {why}"),
                            ))
                        }
                        (None, None) => {
                            return Err(
                                r.err(e, format!("tendon `{tn}` is not a tendon of this model"))
                            )
                        }
                    }
                } else {
                    t.warnings.push(format!(
                        "{}: {}: actuator `{name}` drives neither a joint nor a tendon; ignored",
                        r.files[e.file],
                        r.at(e)
                    ));
                    continue;
                };
                // The ranges that limit (None: unlimited).
                let forcerange = v.limits("force", c.autolimits)?;
                let ctrlrange = v.limits("ctrl", c.autolimits)?;
                let bias = match e.name.as_str() {
                    "general" => v.get("biastype").unwrap_or("none") != "none",
                    "motor" => false,
                    _ => true,
                };
                let gain_fixed = v.get("gaintype").unwrap_or("fixed") == "fixed";
                let (range, source) = if let Some(fr) = forcerange {
                    (Some(fr), LimitSource::Forcerange)
                } else if let Some((lo, hi)) = ctrlrange.filter(|_| !bias && gain_fixed) {
                    let gain = if e.name == "motor" {
                        1.0
                    } else {
                        v.leading("gainprm", 10)?.unwrap_or(1.0)
                    };
                    let (a, b) = (gain * lo, gain * hi);
                    (Some((a.min(b), a.max(b))), LimitSource::Ctrlrange)
                } else {
                    (None, LimitSource::None)
                };
                // (An empty range limits nothing, as MuJoCo's compiler has it.)
                let limit = range
                    .filter(|(lo, hi)| lo < hi)
                    .map(|(lo, hi)| TorqueLimit::from_range(lo, hi));
                actuators.push(Actuator {
                    name,
                    kind: e.name.clone(),
                    drive,
                    limit,
                    limit_source: if limit.is_some() {
                        source
                    } else {
                        LimitSource::None
                    },
                    line: e.line,
                });
            }
        }
        let mut names: HashMap<&str, u32> = HashMap::new();
        for a in &actuators {
            if let Some(prev) = names.insert(&a.name, a.line) {
                return Err(error(
                    source,
                    format!("actuator `{}` (line {})", a.name, a.line),
                    format!("a second actuator of that name (the first is at line {prev})"),
                ));
            }
        }
        for name in &t.ignored {
            t.warnings.push(format!(
                "{source}: <{name}> ignored (outside the statics subset of MJCF)"
            ));
        }
        let model = r.model.clone().unwrap_or_else(|| {
            Path::new(source)
                .file_stem()
                .map_or("mjcf".into(), |s| s.to_string_lossy().into_owned())
        });
        let mut robot = Robot::from_tree(
            model,
            source.to_string(),
            t.links,
            t.link_lines,
            t.joints,
            &t.reference,
            t.warnings,
        )?;
        robot.masses = body_masses(&t.bodies, &t.geom_masses, c, robot.links.len());
        robot.gravity = t.mount.is_none().then_some(gravity);
        robot.sites = t.sites;
        robot.actuators = actuators;
        robot.tendons = spatial_tendons;
        // Springs, each at rest over a range of its length in motion coordinates
        // (q − ref); MuJoCo's default rest length is the length with every joint at its
        // springref (qpos_spring).
        let spring_motion: Vec<f64> = (0..robot.joints.len())
            .map(|j| t.springref.get(&j).copied().unwrap_or(0.0) - t.reference[j])
            .collect();
        let mut springs_out: Vec<Spring> = t
            .joint_springs
            .iter()
            .map(|&(j, k)| Spring {
                name: robot.joints[j].name.clone(),
                on: SpringOn::Joint(j),
                stiffness: k,
                rest: (spring_motion[j], spring_motion[j]),
            })
            .collect();
        for (name, e, k, rest) in springs {
            let (on, rest) = if let Some(terms) = tendons.get(&name) {
                let at_ref: f64 = terms.iter().map(|&(j, c)| c * t.reference[j]).sum();
                let rest = rest.map_or_else(
                    || {
                        let l: f64 = terms.iter().map(|&(j, c)| c * spring_motion[j]).sum();
                        (l, l)
                    },
                    |(lo, hi)| (lo - at_ref, hi - at_ref),
                );
                (SpringOn::Fixed(terms.clone()), rest)
            } else if let Some(tendon) = spatial.get(&name) {
                let tendon = *tendon.as_ref().map_err(|why| {
                    r.err(
                        e,
                        format!("has a spring (stiffness), but cannot be used: {why}"),
                    )
                })?;
                let rest = match rest {
                    Some(r) => r,
                    None => {
                        let pose = robot.pose_full(&spring_motion, |_| true);
                        let (l, _) = robot.tendon_moments(tendon, &pose).map_err(|w| {
                            r.err(e, format!("its rest length (every joint at its springref) puts the side site of geom `{}` inside it, which is not modelled; give springlength", w.geom))
                        })?;
                        (l, l)
                    }
                };
                (SpringOn::Spatial(tendon), rest)
            } else {
                continue;
            };
            springs_out.push(Spring {
                name,
                on,
                stiffness: k,
                rest,
            });
        }
        robot.springs = springs_out;
        Ok(robot)
    }
}
