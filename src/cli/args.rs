//! The arguments shared by subcommands, each group declared once and
//! flattened into the subcommands that take it, and the parsers of the
//! comma-separated numeric flags.

use std::path::PathBuf;

use weldseam::config::{Config, Method};
use weldseam::geometry::pose::RobotPose;
use weldseam::sim::CameraPreset;

/// Which configuration to plan with: `--config` and `--method`.
#[derive(Debug, Clone, clap::Args)]
pub struct ConfigArgs {
    /// Configuration file (TOML); built-in defaults otherwise.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Pipeline variant, overriding pipeline.method of the config.
    #[arg(long, value_enum)]
    pub method: Option<MethodArg>,
}

impl ConfigArgs {
    /// The config file (or the defaults) with the flags' overrides.
    pub fn load(&self) -> anyhow::Result<Config> {
        let mut config = Config::load_or_default(self.config.as_deref())?;
        if let Some(method) = self.method {
            config.pipeline.method = method.into();
        }
        Ok(config)
    }
}

/// `--method`: clap refuses any other name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// The paper's method made robust.
    Robust,
    /// The paper's method exactly as written.
    Paper,
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Self {
        match m {
            MethodArg::Robust => Method::Robust,
            MethodArg::Paper => Method::Paper,
        }
    }
}

/// `--suite` of `eval`: which seeded suite of simulated scenes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum SuiteArg {
    /// The 66 scenes of the paper's camera (`sim::eval_suite`).
    #[default]
    Industrial,
    /// 20 scans of a RealSense-class camera at 200 to 500 mm, made into
    /// cropped:40,voxel:1,metres (`sim::consumer_suite`).
    Consumer,
    /// 24 scans of the same camera at 430 to 500 mm, where its depth noise
    /// is as large as the voxels, handed over the same way
    /// (`sim::consumer::consumer_far_suite`).
    ConsumerFar,
    /// Every fault on every joint type (`sim::fault_suite`): a wrong joint
    /// requested, dropouts along the seam, a clamp, tack welds, spatter,
    /// specular streaks, a plate barely in view, a touching part, glaring
    /// edges.
    Faults,
    /// The industrial suite tilted up to 45 degrees, depth noise up to
    /// 0.15 mm, dropouts up to 5 % (`sim::hard_suite`).
    Hard,
    /// 22 tee joints at 500 to 1000 mm, tilted up to 30 degrees
    /// (`sim::tee_suite`), judged against both fillet roots.
    Tee,
    /// 12 frames of two or three workpieces, each with its own joint
    /// (`sim::multi_suite`), every seam returned matched to the nearest.
    Multi,
    /// 20 corner joints, inside and outside in turn, at 500 to 1000 mm,
    /// tilted up to 30 degrees (`sim::corner_suite`), judged as the tee
    /// suite is against the corner's one weld: an inside corner's root is
    /// planned under `t_fillet` or `auto`, an outside corner is refused, and
    /// a seam returned off that weld, named another joint than `t_fillet`,
    /// or on an outside corner is a confident wrong one.
    Corner,
    /// 12 V-grooves whose bevels end on a flat root land 2.5 to 8 mm wide
    /// (`sim::root_land_suite`), the plates filling the view: planned at
    /// the land's centre with the groove's depth measured down to it.
    RootLand,
    /// 12 tees whose root bends 4 to 16 mm over the seam, a curved wall on
    /// a flat flange or a flange rolled along the seam
    /// (`sim::curved_suite`), planned as t_fillet and auto: every one is
    /// to be refused, none planned as a line.
    Curved,
    /// 12 root-land V-grooves cut 3 to 8 mm wider along part of their
    /// seam, one plate's top edge stepping back while the root runs
    /// straight on (`sim::groove_width_suite`), planned as v_butt and
    /// auto: a seam more than 2 mm off the root is a confident wrong one.
    GrooveWidth,
    /// 16 tees whose web stands 6 to 30 mm from the flange's edge on one
    /// side, the flange wide on the other, seen from either side, the
    /// narrow edge square or rounded, the web's top and the table in view
    /// or cropped away (`sim::web_near_edge_suite`), planned as t_fillet
    /// (or auto, with `--joint-request auto`): each root judged as the tee
    /// suite judges it, a hidden root to be named not planned.
    WebNearEdge,
    /// 16 blocks (cubes or boxes, 30 to 120 mm a side) standing on a
    /// plate, some with a smaller block stacked on them, seen square to a
    /// face or over a corner, the top edges sharp or rounded, the plate
    /// running past the view, ending in it or cropped, the table in view or
    /// cropped (`sim::blocks_suite`), planned as t_fillet (or auto, with
    /// `--joint-request auto`): each block's foot is a fillet root, judged
    /// as the tee suite judges a root, a hidden root to be named not
    /// planned.
    Blocks,
    /// 20 scenes of the weld process (`sim::process_suite`): an I-butt
    /// whose gap opens from 0.5 to 3 mm, a butt with high-low, a 20 mm
    /// plate's 60 degree V-groove, a clamp 15 mm beside a seam, a tee with
    /// a short web; planned with the example procedure (or the config's)
    /// and scored on the figures along the seam, the deposit, the passes
    /// and the torch's clearance.
    Process,
}

/// `--joint-request` of `eval`: how each scene's plan names its joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum JointRequestArg {
    /// The scene's own joint type (a wrong-joint fault's wrong one).
    #[default]
    Scene,
    /// `auto`: the planner decides, and the seam must name the scene's type.
    Auto,
    /// The next type after the scene's (v-butt, i-butt, lap, in turn):
    /// only a refusal is right.
    #[value(name = "wrong-1")]
    Wrong1,
    /// The type after that: only a refusal is right.
    #[value(name = "wrong-2")]
    Wrong2,
    /// V-butt for every scene (and every workpiece of a frame of
    /// several), the groove depth measured.
    #[value(name = "v-butt")]
    VButt,
    /// I-butt for every scene and workpiece.
    #[value(name = "i-butt")]
    IButt,
    /// Lap for every scene and workpiece.
    Lap,
    /// T-fillet for every scene and workpiece: on butt and lap scenes only
    /// a refusal is right.
    #[value(name = "t-fillet")]
    TFillet,
}

/// `--groove-depth` of `eval`: what a V-butt request says of the depth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum GrooveDepthArg {
    /// The scene's depth.
    #[default]
    Given,
    /// None: the planner measures it.
    Measured,
}

/// `--camera` of `simulate`: which simulated camera renders the frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum CameraArg {
    /// The paper's industrial structured-light camera, 1920 x 1200 px.
    #[default]
    Industrial,
    /// A RealSense-class consumer depth camera, 1280 x 720 px over 87 x 58
    /// degrees, depth noise 0.2 % of depth at 0.5 m growing with z squared.
    Consumer,
}

impl From<CameraArg> for CameraPreset {
    fn from(c: CameraArg) -> Self {
        match c {
            CameraArg::Industrial => CameraPreset::Industrial,
            CameraArg::Consumer => CameraPreset::Consumer,
        }
    }
}

/// A plan request's optional settings, the same in `plan` and `controller`.
#[derive(Debug, Clone, clap::Args)]
pub struct RequestArgs {
    /// Groove depth of a V-butt joint, mm. The robust method measures it
    /// when it is not given (where the groove's root is seen) and checks
    /// it against the measurement when it is.
    #[arg(long, allow_negative_numbers = true)]
    pub groove_depth: Option<f64>,
    /// Waypoint spacing, mm (default: trajectory.step_mm of the config).
    #[arg(long, allow_negative_numbers = true)]
    pub step: Option<f64>,
    /// Torch work angle, degrees (default: trajectory.work_angle_deg).
    #[arg(long, allow_hyphen_values = true)]
    pub work_angle: Option<f64>,
    /// Torch travel angle, degrees (default: trajectory.travel_angle_deg).
    #[arg(long, allow_hyphen_values = true)]
    pub travel_angle: Option<f64>,
    /// End_T_Camera for this request instead of robot.hand_eye of the
    /// config: 16 comma-separated numbers, row-major 4x4, mm.
    #[arg(long, allow_hyphen_values = true, value_parser = matrix)]
    pub hand_eye: Option<[f64; 16]>,
}

/// How a cloud file's coordinates are to be read: units and frame.
#[derive(Debug, Clone, Copy, clap::Args)]
pub struct CloudInputArgs {
    /// The cloud's units; auto guesses them from its distances (a median
    /// distance below 20 means metres) and logs the guess.
    #[arg(long, value_enum, default_value_t = UnitsArg::Auto)]
    pub units: UnitsArg,
    /// The cloud's frame: the camera's, or the robot base's (brought into
    /// the camera frame with --pose and the hand-eye before planning).
    #[arg(long, value_enum, default_value_t = CloudFrameArg::Camera)]
    pub cloud_frame: CloudFrameArg,
}

/// The region of interest: `--roi` and `--roi-frame`.
#[derive(Debug, Clone, Copy, clap::Args)]
pub struct RoiArgs {
    /// Plan only the points inside this box: xmin,ymin,zmin,xmax,ymax,zmax
    /// in mm (default: pipeline.roi of the config, else the whole cloud).
    #[arg(long, allow_hyphen_values = true, value_parser = roi_bounds)]
    pub roi: Option<[f64; 6]>,
    /// The frame of --roi: the camera's, or the robot base's (through
    /// --pose and the hand-eye).
    #[arg(long, value_enum, default_value_t = CloudFrameArg::Camera, requires = "roi")]
    pub roi_frame: CloudFrameArg,
}

impl RoiArgs {
    /// The checked box, if one was given.
    pub fn to_library(self) -> anyhow::Result<Option<weldseam::pipeline::roi::Roi>> {
        use weldseam::pipeline::roi::Roi;
        self.roi
            .map(|bounds| Roi::from_bounds(bounds, self.roi_frame.to_library()))
            .transpose()
            .map_err(|e| anyhow::anyhow!("--roi: {e}"))
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum UnitsArg {
    Mm,
    M,
    Auto,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CloudFrameArg {
    Camera,
    Base,
}

impl UnitsArg {
    pub fn to_library(self) -> weldseam::pipeline::Units {
        use weldseam::pipeline::Units;
        match self {
            UnitsArg::Mm => Units::Millimetres,
            UnitsArg::M => Units::Metres,
            UnitsArg::Auto => Units::Auto,
        }
    }
}

impl CloudFrameArg {
    pub fn to_library(self) -> weldseam::pipeline::CloudFrame {
        use weldseam::pipeline::CloudFrame;
        match self {
            CloudFrameArg::Camera => CloudFrame::Camera,
            CloudFrameArg::Base => CloudFrame::Base,
        }
    }
}

/// Parses exactly `N` comma-separated numbers, naming the flag in errors.
pub fn numbers<const N: usize>(flag: &str, text: &str) -> Result<[f64; N], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != N {
        return Err(format!("{flag} needs {N} comma-separated numbers, got {}: {text:?}", parts.len()));
    }
    let mut out = [0.0; N];
    for (k, part) in parts.iter().enumerate() {
        let v: f64 = part.parse().map_err(|_| format!("{flag}: value {} ({part:?}) is not a number", k + 1))?;
        if !v.is_finite() {
            return Err(format!("{flag}: value {} is not finite", k + 1));
        }
        out[k] = v;
    }
    Ok(out)
}

/// `x,y,z,rx,ry,rz` in mm and degrees.
pub fn pose(text: &str) -> Result<RobotPose, String> {
    let v = numbers::<6>("--pose", text)?;
    Ok(RobotPose { xyz_mm: [v[0], v[1], v[2]], angles_deg: [v[3], v[4], v[5]] })
}

/// Sixteen numbers, a row-major 4x4 matrix.
pub fn matrix(text: &str) -> Result<[f64; 16], String> {
    numbers::<16>("--hand-eye", text)
}

/// `xmin,ymin,zmin,xmax,ymax,zmax` in mm.
pub fn roi_bounds(text: &str) -> Result<[f64; 6], String> {
    numbers::<6>("--roi", text)
}

/// `x,y,z` in mm.
pub fn point(text: &str) -> Result<[f64; 3], String> {
    numbers::<3>("--start-near", text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_accepts_negative_values_and_spaces() {
        let p = pose("-613.5, -284.81,296.28,178.28,1.04,-107.12").unwrap();
        assert_eq!(p.xyz_mm, [-613.5, -284.81, 296.28]);
        assert_eq!(p.angles_deg[2], -107.12);
    }

    #[test]
    fn bad_poses_say_what_is_wrong() {
        assert!(pose("1,2,3").unwrap_err().contains("needs 6"));
        assert!(pose("1,2,3,4,5,x").unwrap_err().contains("value 6"));
        assert!(pose("1,2,3,4,5,nan").unwrap_err().contains("not finite"));
    }
}
