//! Real scans against measured references: the public scans of
//! real-scans/manifest.toml, each with what a right answer is in
//! real-scans/references.toml.
//!
//! A scan with a plane root in view has its root measured from the cloud
//! itself: the faces that meet at the root are each fitted (least squares,
//! [`crate::geometry::fit::Moments::plane`]) to the points inside a hand-picked axis-aligned box
//! in the cloud's own coordinates, the root is where the planes meet, and
//! the stretch of it the camera sees is where both faces are seen within a
//! few millimetres of it ([`mod@reference`]). A V-groove with a flat root land
//! has its root where the planner's weld line should run: the middle of
//! the land at the land's height (the paper's Eq. 32 puts the line on the
//! groove's centre at the depth where the bevels end, and a land is where
//! they end), so its reference is the line halfway between where each
//! flank meets the land. A scan with no plane root to plan has its expected
//! outcome instead: refused, with the class of reason and the rule ids
//! that state it.
//!
//! A root may carry a second reasonable choice of boxes (`alternative`):
//! it is measured from both and kept only if the two lines lie within
//! [`reference::MAX_BOX_CHOICE_MM`] of each other at the visible
//! stretch's ends, so the reference says how steady it is; a plan is then
//! judged against both lines, each waypoint by the farther. It may carry
//! `check` stretches of the flange, measured against the flange's plane
//! but not fitted: where the camera shows the flange off its plane (a
//! strip in an inside corner), in figures anyone can recompute. A tee
//! whose flange is seen only as a narrow sliver has the square-top kind
//! ([`mod@square_top`]).
//!
//! The references file holds the boxes (chosen by a person looking at the
//! cloud, with a sentence each on how) and the figures measured from them,
//! never a point of a scan: the scans' licences forbid copying them, and
//! anyone holding the files can recompute every figure
//! (`weldseam eval --real-scans real-scans --check-references`, with
//! [`reference::differs`] as the comparison). [`score()`] judges a plan against a reference the
//! way the simulated suites are judged: right, refused (and whether for the
//! expected reason), short of the bar, or confident wrong.

pub mod reference;
pub mod score;
pub mod square_top;
#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::joint::JointType;

pub use reference::{MeasureError, MeasuredPlane, MeasuredRoot, measure_root};
pub use score::{RootScore, ScanScore, SeamScore, Verdict, score};

/// How far a planned seam may lie from a tee's (or lap's, or I-butt's)
/// reference root, mm, and how much of the visible root it must cover
/// within that: the bar for the robotic-sealing tees.
pub const TEE_BAR_MM: f64 = 1.0;
/// The share of a tee's visible root a right plan covers within the bar.
pub const TEE_MIN_COVERAGE: f64 = 0.90;
/// A V-groove's bar, mm: its root is read under a wider bead and from a
/// groove whose bottom the camera sees less of.
pub const GROOVE_BAR_MM: f64 = 1.5;
/// The share of a V-groove's visible root a right plan covers within the
/// bar.
pub const GROOVE_MIN_COVERAGE: f64 = 0.85;
/// A planned seam this far from every reference root anywhere along it, mm,
/// is a confident wrong one: a torch this far off misses the joint.
pub const CONFIDENT_WRONG_MM: f64 = 2.0;

/// The bar a seam of this joint type is held to: distance, mm, and the
/// least share of the visible root covered within it.
pub fn bar_for(joint: JointType) -> (f64, f64) {
    match joint {
        JointType::VButt => (GROOVE_BAR_MM, GROOVE_MIN_COVERAGE),
        _ => (TEE_BAR_MM, TEE_MIN_COVERAGE),
    }
}

/// Why the real-scan folder cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum RealScanError {
    #[error("cannot read {path}: {source}")]
    Read { path: PathBuf, source: std::io::Error },
    #[error("{path} is not valid: {source}")]
    Parse { path: PathBuf, source: toml::de::Error },
    #[error("{path}: {problem}")]
    Invalid { path: PathBuf, problem: String },
}

/// One scan of real-scans/manifest.toml (the fields the eval reads).
#[derive(Debug, Clone, Deserialize)]
pub struct ManifestScan {
    pub id: String,
    pub family: String,
    #[serde(default)]
    pub shows: String,
}

#[derive(Debug, Deserialize)]
struct Manifest {
    #[serde(default)]
    scan: Vec<ManifestScan>,
}

/// What a right answer on a scan is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Expect {
    /// A plane root is in view: its seam is to be planned.
    Planned,
    /// Nothing in view is a plane weld to plan: only a refusal is right.
    Refused,
}

/// The reasons a refusal may give that are right on a scan with nothing
/// to plan, by what the cloud shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RefusalClass {
    /// The members meet along a curve, not a straight line.
    CurvedRoot,
    /// Only the groove's two flank faces are in view, no plate top.
    NoPlateTop,
    /// The cloud cannot be a camera-frame view under the pose given.
    NotCameraFrame,
}

impl RefusalClass {
    pub fn describe(self) -> &'static str {
        match self {
            RefusalClass::CurvedRoot => "curved root",
            RefusalClass::NoPlateTop => "no plate top in view",
            RefusalClass::NotCameraFrame => "not a camera-frame view",
        }
    }
}

/// The refusal a scan with nothing to plan expects.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ExpectedRefusal {
    pub class: RefusalClass,
    /// The ids of the rules that state this class of reason; empty while
    /// no rule of the rulebook states it (then no refusal counts as
    /// refused for the right reason).
    #[serde(default)]
    pub rules: Vec<String>,
    /// What in the cloud makes it this class, in a sentence.
    pub why: String,
}

/// An axis-aligned box in the cloud's own coordinates and units.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AxisBox {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

impl AxisBox {
    pub fn contains(&self, p: &[f64; 3]) -> bool {
        (0..3).all(|i| p[i] >= self.min[i] && p[i] <= self.max[i])
    }
}

/// One face of a root: the points inside any of its boxes (a face that
/// runs askew to the cloud's axes is picked with several boxes along it).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FaceBox {
    pub name: String,
    pub boxes: Vec<AxisBox>,
}

impl FaceBox {
    pub fn contains(&self, p: &[f64; 3]) -> bool {
        self.boxes.iter().any(|b| b.contains(p))
    }
}

/// How the faces make the root.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RootKind {
    /// Two faces meet at the root (a tee's flange and web, an inside
    /// corner, a V-groove without a land): the line where their planes
    /// meet. Two boxes.
    Meet,
    /// A V-groove with a flat root land: flank, flank, land; the line on
    /// the land halfway between where each flank meets it. Three boxes.
    LandCentre,
    /// A tee whose flange in view is a narrow sliver of a box section's
    /// top: standing face, sliver, the section's side face; the top is
    /// fitted square to the standing face and checked square to the side
    /// ([`mod@square_top`]), and the root is where it meets the standing
    /// face. Three boxes.
    SquareTop,
}

/// One reference root of a scan.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RootReference {
    pub name: String,
    pub kind: RootKind,
    #[serde(rename = "face")]
    pub faces: Vec<FaceBox>,
    /// A second reasonable choice of boxes for the same faces: the root
    /// is kept only if it moves less than
    /// [`reference::MAX_BOX_CHOICE_MM`] between the two.
    #[serde(default)]
    pub alternative: Vec<FaceBox>,
    /// Stretches of the flange not fitted but measured against its plane
    /// (each one's points' median distance from it): where the camera
    /// shows the flange off the plane it is fitted to, such as a strip
    /// beside the web in an inside corner.
    #[serde(default, rename = "check")]
    pub checks: Vec<FaceBox>,
    /// The figures measured from the boxes (written by
    /// `eval --real-scans DIR --bless-references`, checked by
    /// `--check-references`).
    pub measured: Option<MeasuredRoot>,
}

/// What is right on one scan.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScanReference {
    pub id: String,
    /// The joint type the scan's family is: what the typed plan requests
    /// (`v_butt`, `t_fillet`, ...).
    #[serde(deserialize_with = "joint_type")]
    pub joint: JointType,
    pub expect: Expect,
    /// How the boxes were chosen, in a sentence (scans with a root).
    #[serde(default)]
    pub how: Option<String>,
    #[serde(default, rename = "root")]
    pub roots: Vec<RootReference>,
    #[serde(default)]
    pub refusal: Option<ExpectedRefusal>,
}

/// A joint type by any of the names [`JointType`]'s `FromStr` accepts.
fn joint_type<'de, D: serde::Deserializer<'de>>(d: D) -> Result<JointType, D::Error> {
    let name = String::deserialize(d)?;
    name.parse().map_err(serde::de::Error::custom)
}

/// The references file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct References {
    /// Millimetres per unit of the clouds' coordinates (1000 for metres):
    /// the boxes are in the cloud's units, every measured figure in mm.
    pub mm_per_unit: f64,
    #[serde(default, rename = "scan")]
    pub scans: Vec<ScanReference>,
}

/// A real-scan folder: manifest.toml, references.toml and files/.
#[derive(Debug, Clone)]
pub struct RealScans {
    pub dir: PathBuf,
    pub manifest: Vec<ManifestScan>,
    pub references: References,
}

/// The file names inside a real-scan folder.
pub const MANIFEST_FILE: &str = "manifest.toml";
pub const REFERENCES_FILE: &str = "references.toml";

fn read(path: &Path) -> Result<String, RealScanError> {
    std::fs::read_to_string(path).map_err(|source| RealScanError::Read { path: path.into(), source })
}

impl RealScans {
    /// Reads the folder's manifest and references and checks they agree:
    /// every reference names a scan of the manifest, and a scan's reference
    /// has what its expectation needs.
    pub fn load(dir: &Path) -> Result<RealScans, RealScanError> {
        let manifest_path = dir.join(MANIFEST_FILE);
        let manifest: Manifest = toml::from_str(&read(&manifest_path)?)
            .map_err(|source| RealScanError::Parse { path: manifest_path.clone(), source })?;
        let references_path = dir.join(REFERENCES_FILE);
        let references = parse_references(&read(&references_path)?).map_err(|e| e.with_path(&references_path))?;
        let invalid = |problem: String| RealScanError::Invalid { path: references_path.clone(), problem };
        for r in &references.scans {
            if !manifest.scan.iter().any(|m| m.id == r.id) {
                return Err(invalid(format!("scan {} is not in {MANIFEST_FILE}", r.id)));
            }
        }
        Ok(RealScans { dir: dir.into(), manifest: manifest.scan, references })
    }

    /// The cloud file of a scan.
    pub fn file(&self, id: &str) -> PathBuf {
        self.dir.join("files").join(format!("{id}.pcd"))
    }

    /// The reference of a scan, if the file has one.
    pub fn reference(&self, id: &str) -> Option<&ScanReference> {
        self.references.scans.iter().find(|r| r.id == id)
    }
}

/// A references file's problem before its path is known.
#[derive(Debug)]
pub enum ParseProblem {
    Toml(toml::de::Error),
    Invalid(String),
}

impl ParseProblem {
    fn with_path(self, path: &Path) -> RealScanError {
        match self {
            ParseProblem::Toml(source) => RealScanError::Parse { path: path.into(), source },
            ParseProblem::Invalid(problem) => RealScanError::Invalid { path: path.into(), problem },
        }
    }
}

/// Parses a references file and checks each scan's entry is complete: a
/// planned scan has roots of the right number of boxes and no refusal, a
/// refused one a refusal and no roots.
pub fn parse_references(text: &str) -> Result<References, ParseProblem> {
    let references: References = toml::from_str(text).map_err(ParseProblem::Toml)?;
    if !(references.mm_per_unit.is_finite() && references.mm_per_unit > 0.0) {
        return Err(ParseProblem::Invalid(format!("mm_per_unit {} is not a positive number", references.mm_per_unit)));
    }
    for r in &references.scans {
        let problem = match (r.expect, r.roots.is_empty(), &r.refusal) {
            (Expect::Planned, true, _) => Some("expects a plan but has no root"),
            (Expect::Planned, _, Some(_)) => Some("expects a plan but names a refusal"),
            (Expect::Refused, _, None) => Some("expects a refusal but names none"),
            (Expect::Refused, false, _) => Some("expects a refusal but has roots"),
            _ => None,
        };
        if let Some(p) = problem {
            return Err(ParseProblem::Invalid(format!("scan {}: {p}", r.id)));
        }
        for root in &r.roots {
            let needed = match root.kind {
                RootKind::Meet => 2,
                RootKind::LandCentre | RootKind::SquareTop => 3,
            };
            if root.faces.len() != needed || !(root.alternative.is_empty() || root.alternative.len() == needed) {
                return Err(ParseProblem::Invalid(format!(
                    "scan {}, root {:?}: {} boxes, a {:?} root needs {needed}",
                    r.id,
                    root.name,
                    root.faces.len(),
                    root.kind
                )));
            }
        }
    }
    Ok(references)
}
