//! The planner's own settings: the `[pipeline]`, `[paper]` and
//! `[trajectory]` sections, their defaults and their checks.

use serde::{Deserialize, Deserializer};

use crate::geometry::region::{CloudFrame, Roi};

use super::{
    ConfigError, MAX_STEP_MM, MAX_TORCH_ANGLE_DEG, MIN_FILLET_WORK_ANGLE_DEG, MIN_STEP_MM, check, count_in, in_range,
};

/// Which variant of the pipeline runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// The paper's method made robust (the default).
    #[default]
    Robust,
    /// The paper's method exactly as written, for comparison.
    Paper,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Robust => "robust",
            Method::Paper => "paper",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "robust" => Some(Method::Robust),
            "paper" => Some(Method::Paper),
            _ => None,
        }
    }
}

/// Reads `pipeline.method` by name; the error names the key, as the
/// range checks' do.
fn method_by_name<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Method, D::Error> {
    let name = String::deserialize(deserializer)?;
    Method::from_name(&name).ok_or_else(|| {
        serde::de::Error::custom(format!(
            "config key `pipeline.method`: unknown method {name:?}; expected \"robust\" or \"paper\""
        ))
    })
}

/// Where the neighbour count a full plane gives comes from, against which
/// the plane and edge criteria measure each point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointDensity {
    /// The camera model for organized frames (a raw frame of the camera),
    /// the cloud's own measured spacing for any other cloud.
    #[default]
    Auto,
    /// Always the camera model (the paper's Eq. 4 to 14): for comparison.
    Camera,
    /// Always the cloud's measured spacing, organized frames too.
    Measured,
}

/// The frame a config's region of interest is given in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RoiFrame {
    /// The camera's optical frame.
    #[default]
    Camera,
    /// The robot base frame, through each request's pose and hand-eye.
    Base,
}

impl RoiFrame {
    pub fn cloud_frame(self) -> CloudFrame {
        match self {
            RoiFrame::Camera => CloudFrame::Camera,
            RoiFrame::Base => CloudFrame::Base,
        }
    }
}

/// Parameters of the seam pipeline's stages: the `[pipeline]` section.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PipelineParams {
    #[serde(deserialize_with = "method_by_name")]
    pub method: Method,
    /// Neighbour search radius R, mm (paper: 1). For a cloud whose density
    /// is measured, the radius at which a full plane holds about 50 points
    /// when that is larger.
    pub neighbour_radius_mm: f64,
    /// Where the full-plane neighbour count comes from.
    pub point_density: PointDensity,
    /// Robust plane criterion: the least fraction of the neighbours a full
    /// plane would give at this point, tilt and pixel grid included.
    pub plane_min_neighbour_ratio: f64,
    /// Robust plane criterion: the largest angle between a point's local
    /// normal and the workpiece's dominant normal; rejects bevel and side
    /// faces, which the neighbour count cannot tell from plates.
    pub plane_max_normal_angle_deg: f64,
    /// Euclidean clustering tolerance, mm, for clouds without a pixel grid
    /// (organized clouds are clustered on the grid, which keeps sub-mm gaps).
    pub cluster_tolerance_mm: f64,
    /// Clusters smaller than this are noise, not planes.
    pub min_plane_area_mm2: f64,
    /// Two butt plates are coplanar when their planes' offsets differ by
    /// less than this.
    pub coplanar_tolerance_mm: f64,
    /// The range of plate thicknesses a lap step may have.
    pub lap_step_min_mm: f64,
    pub lap_step_max_mm: f64,
    /// A tee's web: its top lies more than `lap_step_max_mm` (or, a short
    /// web under `t_fillet`, 1.5 times its width) and at most this far over
    /// the flange, mm ...
    pub tee_web_height_max_mm: f64,
    /// ... and is at most this wide, mm (the web's thickness; a plate
    /// lying over the table is far wider).
    pub tee_web_thickness_max_mm: f64,
    /// Robust edge criterion: a plane point is an edge point when it has at
    /// most this fraction of its full-plane neighbour count (paper: 0.5).
    pub edge_max_neighbour_ratio: f64,
    /// RANSAC inlier distance, mm (paper: 1).
    pub ransac_distance_mm: f64,
    pub ransac_iterations: u32,
    /// A line needs at least this many inliers to count as an edge.
    pub ransac_min_line_points: u32,
    /// Stop segmenting when fewer edge points remain (section 3.4.2).
    pub ransac_min_remaining_points: u32,
    pub ransac_max_lines: u32,
    /// Seed of the RANSAC random generator, so results are reproducible.
    pub ransac_seed: u64,
    /// The two weld edges must be parallel within this angle.
    pub max_edge_angle_deg: f64,
    /// Half-width of the band around a coarse weld edge searched for the
    /// plate's true boundary, mm.
    pub boundary_band_mm: f64,
    /// A point lies on a plate's plane when within this distance of it.
    /// Beside a tee's root, the flange's points are read within the wider
    /// of this and 2.5 times the flange's measured scatter
    /// (`pipeline::fillet`), since a noisier camera's flange would lose its
    /// points there.
    pub on_plane_tolerance_mm: f64,
    /// Degree n of the least-squares polynomial (Eq. 17); 1 for straight seams.
    pub fit_degree: u32,
    /// Boundary samples further than this many sigmas from the fit are
    /// dropped and the fit repeated (sigma: the median residual taken as a
    /// standard deviation, so a run of cut-short samples cannot widen it).
    pub fit_trim_sigma: f64,
    /// Region of interest of every plan whose request names none:
    /// `[xmin, ymin, zmin, xmax, ymax, zmax]`, mm; empty for the whole cloud.
    pub roi: Vec<f64>,
    /// The frame `roi` is given in.
    pub roi_frame: RoiFrame,
}

impl Default for PipelineParams {
    fn default() -> Self {
        PipelineParams {
            method: Method::Robust,
            neighbour_radius_mm: 1.0,
            point_density: PointDensity::Auto,
            plane_min_neighbour_ratio: 0.8,
            plane_max_normal_angle_deg: 20.0,
            cluster_tolerance_mm: 1.0,
            min_plane_area_mm2: 400.0,
            coplanar_tolerance_mm: 3.0,
            lap_step_min_mm: 1.0,
            lap_step_max_mm: 30.0,
            tee_web_height_max_mm: 250.0,
            tee_web_thickness_max_mm: 30.0,
            edge_max_neighbour_ratio: 0.75,
            ransac_distance_mm: 1.0,
            ransac_iterations: 400,
            ransac_min_line_points: 40,
            ransac_min_remaining_points: 40,
            ransac_max_lines: 12,
            ransac_seed: 42,
            max_edge_angle_deg: 10.0,
            boundary_band_mm: 3.0,
            on_plane_tolerance_mm: 0.4,
            fit_degree: 1,
            fit_trim_sigma: 3.0,
            roi: Vec::new(),
            roi_frame: RoiFrame::Camera,
        }
    }
}

/// The paper's own numbers where they differ from the robust method's:
/// the `[paper]` section.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PaperParams {
    /// μ of the plane edge criterion (Eq. 15).
    pub edge_ratio: f64,
    /// Euclidean clustering threshold (section 3.3).
    pub cluster_tolerance_mm: f64,
}

impl Default for PaperParams {
    fn default() -> Self {
        PaperParams { edge_ratio: 0.5, cluster_tolerance_mm: 2.0 }
    }
}

/// Sampling and torch orientation of the trajectory: the `[trajectory]`
/// section, and what a request's own step and angles override.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrajectoryParams {
    /// Distance between waypoints along the seam, mm.
    pub step_mm: f64,
    /// Torch tilt about tool x, the travel direction, degrees.
    pub work_angle_deg: f64,
    /// Torch tilt about tool y, across the seam in the plate's plane
    /// (push positive), degrees.
    pub travel_angle_deg: f64,
    /// Tee joints: the torch axis's angle from the flange, degrees, in the
    /// plane across the root, leaning towards the web (45: the bisector of
    /// a square tee's corner). `work_angle_deg` tilts it further, as for
    /// every joint; a request's work angle overrides that, not this.
    pub fillet_work_angle_deg: f64,
}

impl Default for TrajectoryParams {
    fn default() -> Self {
        TrajectoryParams { step_mm: 5.0, work_angle_deg: 0.0, travel_angle_deg: 0.0, fillet_work_angle_deg: 45.0 }
    }
}

impl PipelineParams {
    /// Checks the `[pipeline]` section.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let p = self;
        in_range("pipeline.neighbour_radius_mm", p.neighbour_radius_mm, 0.05, 10.0)?;
        in_range("pipeline.plane_min_neighbour_ratio", p.plane_min_neighbour_ratio, 0.05, 1.0)?;
        in_range("pipeline.plane_max_normal_angle_deg", p.plane_max_normal_angle_deg, 1.0, 89.0)?;
        in_range("pipeline.cluster_tolerance_mm", p.cluster_tolerance_mm, 0.05, 20.0)?;
        in_range("pipeline.min_plane_area_mm2", p.min_plane_area_mm2, 0.0, 1e7)?;
        in_range("pipeline.coplanar_tolerance_mm", p.coplanar_tolerance_mm, 0.05, 50.0)?;
        in_range("pipeline.lap_step_min_mm", p.lap_step_min_mm, 0.1, 100.0)?;
        in_range("pipeline.lap_step_max_mm", p.lap_step_max_mm, 0.1, 200.0)?;
        check("pipeline.lap_step_max_mm", p.lap_step_max_mm > p.lap_step_min_mm, || {
            format!("must exceed lap_step_min_mm ({}), got {}", p.lap_step_min_mm, p.lap_step_max_mm)
        })?;
        in_range("pipeline.tee_web_height_max_mm", p.tee_web_height_max_mm, 1.0, 2000.0)?;
        check("pipeline.tee_web_height_max_mm", p.tee_web_height_max_mm > p.lap_step_max_mm, || {
            format!(
                "must exceed lap_step_max_mm ({}): a web is taller than a lap's step, got {}",
                p.lap_step_max_mm, p.tee_web_height_max_mm
            )
        })?;
        in_range("pipeline.tee_web_thickness_max_mm", p.tee_web_thickness_max_mm, 0.5, 500.0)?;
        in_range("pipeline.edge_max_neighbour_ratio", p.edge_max_neighbour_ratio, 0.05, 0.99)?;
        check("pipeline.edge_max_neighbour_ratio", p.edge_max_neighbour_ratio < p.plane_min_neighbour_ratio, || {
            format!(
                "must be below plane_min_neighbour_ratio ({}), or every plane point is an edge point",
                p.plane_min_neighbour_ratio
            )
        })?;
        in_range("pipeline.ransac_distance_mm", p.ransac_distance_mm, 0.01, 20.0)?;
        count_in("pipeline.ransac_iterations", p.ransac_iterations.into(), 1, 100_000)?;
        count_in("pipeline.ransac_min_line_points", p.ransac_min_line_points.into(), 2, 1_000_000)?;
        count_in("pipeline.ransac_min_remaining_points", p.ransac_min_remaining_points.into(), 2, 1_000_000)?;
        count_in("pipeline.ransac_max_lines", p.ransac_max_lines.into(), 1, 100)?;
        in_range("pipeline.max_edge_angle_deg", p.max_edge_angle_deg, 0.1, 45.0)?;
        in_range("pipeline.boundary_band_mm", p.boundary_band_mm, 0.1, 50.0)?;
        in_range("pipeline.on_plane_tolerance_mm", p.on_plane_tolerance_mm, 0.01, 10.0)?;
        check("pipeline.fit_degree", (1..=5).contains(&p.fit_degree), || {
            format!("must be 1 (straight seams) to 5, got {}", p.fit_degree)
        })?;
        in_range("pipeline.fit_trim_sigma", p.fit_trim_sigma, 1.0, 100.0)?;
        self.region_of_interest().map(|_| ())
    }

    /// The configured region of interest, or None for the whole cloud;
    /// the error names `pipeline.roi` and the limit it breaks.
    pub fn region_of_interest(&self) -> Result<Option<Roi>, ConfigError> {
        let bounds: [f64; 6] = match self.roi.as_slice().try_into() {
            Ok(bounds) => bounds,
            Err(_) if self.roi.is_empty() => return Ok(None),
            Err(_) => {
                return Err(ConfigError::Invalid {
                    key: "pipeline.roi",
                    message: format!(
                        "must be [] or 6 numbers [xmin, ymin, zmin, xmax, ymax, zmax], got {}",
                        self.roi.len()
                    ),
                });
            }
        };
        Roi::from_bounds(bounds, self.roi_frame.cloud_frame())
            .map(Some)
            .map_err(|e| ConfigError::Invalid { key: "pipeline.roi", message: format!("must be a box: {e}") })
    }
}

impl PaperParams {
    /// Checks the `[paper]` section.
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_range("paper.edge_ratio", self.edge_ratio, 0.01, 1.0)?;
        in_range("paper.cluster_tolerance_mm", self.cluster_tolerance_mm, 0.05, 20.0)
    }
}

impl TrajectoryParams {
    /// Checks the `[trajectory]` section, against the same limits a
    /// request's own step and angles are held to.
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_range("trajectory.step_mm", self.step_mm, MIN_STEP_MM, MAX_STEP_MM)?;
        in_range("trajectory.work_angle_deg", self.work_angle_deg, -MAX_TORCH_ANGLE_DEG, MAX_TORCH_ANGLE_DEG)?;
        in_range("trajectory.travel_angle_deg", self.travel_angle_deg, -MAX_TORCH_ANGLE_DEG, MAX_TORCH_ANGLE_DEG)?;
        // The torch must lean between the flange and the web, never along
        // either.
        let (least, most) = (MIN_FILLET_WORK_ANGLE_DEG, 90.0 - MIN_FILLET_WORK_ANGLE_DEG);
        in_range("trajectory.fillet_work_angle_deg", self.fillet_work_angle_deg, least, most)
    }
}
