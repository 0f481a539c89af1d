//! What the planner sees in a cloud before planning it, for a person
//! commissioning a camera (`weldseam inspect`): its organization, the units
//! it seems to be in, its depth range, whether it can be a camera's view,
//! the intrinsics of an organized frame, whether an unorganized one is a
//! raw frame without its grid, its point spacing by depth, and so which
//! rule the plane and edge criteria would measure it by.
//!
//! Every figure comes from the same functions `plan` uses, so the survey
//! cannot disagree with what planning does.

use crate::camera::{IntrinsicsEstimate, estimate_intrinsics};
use crate::cloud::PointCloud;
use crate::config::{Config, PointDensity};

use super::input::{self, AngularExtent, UnitsGuess, View, ViewCounts};
use super::regrid::{self, Regridded};
use super::scale;

/// Depth bands the spacing is measured in, at most: enough to see how the
/// spacing grows with depth, few enough to read at a glance.
const DEPTH_BANDS: usize = 4;

/// The fewest points a depth band is measured on.
const MIN_BAND_POINTS: usize = 500;

/// The spacing of the points in one band of depth.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthBand {
    pub from_mm: f64,
    pub to_mm: f64,
    pub points: usize,
    /// `None` when the band's points are too sparse to measure.
    pub spacing_mm: Option<f64>,
}

/// What the planner sees in a cloud.
#[derive(Debug, Clone, PartialEq)]
pub struct Survey {
    pub points: usize,
    pub valid: usize,
    /// Width and height of an organized cloud.
    pub grid: Option<(usize, usize)>,
    pub units: UnitsGuess,
    /// Least and greatest depth of the valid points, mm (after the units
    /// guess).
    pub depth_mm: Option<(f64, f64)>,
    /// Where the valid points lie against any camera's view, as the input
    /// step counts them before planning: many behind the camera or beyond
    /// any field of view and the cloud is not a camera-frame view (it may
    /// be in the robot base frame).
    pub view: ViewCounts,
    /// How wide the valid points spread as seen from the camera's origin,
    /// as the input step reads it: wider than any camera sees and the
    /// cloud is not a camera-frame view either.
    pub extent: Option<AngularExtent>,
    /// An organized frame's own pinhole.
    pub intrinsics: Option<IntrinsicsEstimate>,
    /// For an unorganized cloud: put back on the configured camera's grid,
    /// or why not.
    pub regrid: Option<Result<Regridded, String>>,
    /// The spacing of the whole cloud, mm, and by depth.
    pub spacing_mm: Option<f64>,
    pub bands: Vec<DepthBand>,
    /// Whether `plan` measures the full-plane count from the cloud (else it
    /// takes the camera model's), and the neighbour radius it would use.
    pub measured_density: bool,
    pub radius_mm: f64,
}

/// Surveys `cloud` as `plan` would see it with `config`.
pub fn survey(cloud: &PointCloud, config: &Config) -> Survey {
    let units = input::guess_units(cloud);
    let in_mm = if units.metres { input::metres_to_millimetres(cloud) } else { cloud.clone() };
    let valid: Vec<[f32; 3]> = in_mm.points().iter().copied().filter(|p| p[0].is_finite()).collect();
    let depth_mm = valid
        .iter()
        .map(|p| p[2] as f64)
        .fold(None, |range: Option<(f64, f64)>, z| Some(range.map_or((z, z), |(lo, hi)| (lo.min(z), hi.max(z)))));

    let regrid = (!in_mm.is_organized())
        .then(|| regrid::regrid(&in_mm, &config.camera).map(|(_, done)| done).map_err(|why| why.to_string()));
    let raw_frame = in_mm.is_organized() || matches!(regrid, Some(Ok(_)));
    let measured_density = match config.pipeline.point_density {
        PointDensity::Camera => false,
        PointDensity::Measured => true,
        PointDensity::Auto => !raw_frame,
    };
    let configured = config.pipeline.neighbour_radius_mm;
    let spacing_mm = scale::measure_spacing(&in_mm, configured).ok().map(|s| s.spacing_mm);
    let radius_mm = match (measured_density, spacing_mm) {
        (true, Some(s)) => scale::radius_for(s, configured),
        _ => configured,
    };
    Survey {
        points: cloud.len(),
        valid: valid.len(),
        grid: cloud.is_organized().then(|| (cloud.width(), cloud.height())),
        units,
        depth_mm,
        view: ViewCounts::of(&in_mm),
        extent: AngularExtent::of(&in_mm),
        intrinsics: estimate_intrinsics(&in_mm),
        regrid,
        spacing_mm,
        bands: depth_bands(&valid, configured),
        measured_density,
        radius_mm,
    }
}

impl Survey {
    /// Whether the cloud can be a camera-frame view, by the input step's
    /// own measures ([`input::view_of`]).
    pub fn frame_view(&self) -> View {
        input::view_of(&self.view, self.extent.as_ref())
    }
}

/// The spacing in bands of equal point count along depth.
fn depth_bands(valid: &[[f32; 3]], start_mm: f64) -> Vec<DepthBand> {
    let mut by_depth = valid.to_vec();
    by_depth.sort_unstable_by(|a, b| a[2].total_cmp(&b[2]));
    let bands = (by_depth.len() / MIN_BAND_POINTS).clamp(1, DEPTH_BANDS);
    let per_band = by_depth.len().div_ceil(bands).max(1);
    by_depth
        .chunks(per_band)
        .filter(|band| !band.is_empty())
        .map(|band| {
            let sub = PointCloud::unorganized(band.to_vec());
            DepthBand {
                from_mm: band[0][2] as f64,
                to_mm: band[band.len() - 1][2] as f64,
                points: band.len(),
                spacing_mm: scale::measure_spacing(&sub, start_mm).ok().map(|s| s.spacing_mm),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraModel;
    use crate::sim::{demo_scene, simulate};

    #[test]
    fn a_raw_frame_and_its_voxel_grid_in_metres_are_told_apart() {
        let config = Config::default();
        let sim = simulate(&demo_scene(crate::joint::JointType::IButt), &CameraModel::default());
        let raw = survey(&sim.cloud, &config);
        assert_eq!(raw.grid, Some((1920, 1200)));
        assert!(!raw.units.metres && !raw.measured_density && raw.radius_mm == 1.0);
        let fx = raw.intrinsics.as_ref().map(|e| e.intrinsics.fx).unwrap();
        assert!((fx / config.camera.fx() - 1.0).abs() < 1e-3, "fx {fx}");
        assert!(raw.view.behind == 0 && raw.view.beyond_any_view == 0);

        // Every fourth point of every fourth row, in metres, unorganized:
        // a sparse cloud that no grid fits.
        let w = sim.cloud.width();
        let sparse: Vec<[f32; 3]> = (0..sim.cloud.len())
            .filter(|i| (i % w).is_multiple_of(4) && (i / w).is_multiple_of(4))
            .map(|i| sim.cloud.points()[i])
            .filter(|p| p[0].is_finite())
            .map(|p| p.map(|c| c * 1e-3))
            .collect();
        let seen = survey(&PointCloud::unorganized(sparse), &config);
        assert!(seen.units.metres && seen.grid.is_none() && seen.intrinsics.is_none());
        assert!(matches!(seen.regrid, Some(Err(_))), "{:?}", seen.regrid);
        assert!(seen.measured_density && seen.radius_mm > 1.0);
        let (spacing, raw_spacing) = (seen.spacing_mm.unwrap(), raw.spacing_mm.unwrap());
        assert!((spacing / raw_spacing - 4.0).abs() < 1.0, "{spacing} against {raw_spacing}");
        let (near, far) = (seen.depth_mm.unwrap().0, seen.depth_mm.unwrap().1);
        assert!(near > 100.0 && far < 3000.0, "depth in mm after the units guess: {near} to {far}");
        let bands = &seen.bands;
        assert!(bands.len() >= 2 && bands.windows(2).all(|b| b[0].to_mm <= b[1].from_mm), "{bands:?}");
    }

    #[test]
    fn every_variant_of_a_capture_is_surveyed_as_what_it_is() {
        use crate::sim::variants::Variant;
        let config = Config::default();
        let sim = simulate(&demo_scene(crate::joint::JointType::VButt), &CameraModel::default());
        let of = |text: &str| survey(&Variant::parse(text).unwrap().apply(&sim, 5).cloud, &config);
        let raw = of("raw");
        assert_eq!(of("compressed"), raw, "a compressed PCD is the frame itself");
        // Without its grid, the raw frame is put back on the camera's.
        let unorganized = of("unorganized");
        assert!(unorganized.grid.is_none() && matches!(unorganized.regrid, Some(Ok(_))));
        assert!(!unorganized.measured_density && unorganized.depth_mm == raw.depth_mm);
        // In metres, guessed so; in the base frame, no camera's view.
        let metres = of("metres");
        assert!(metres.units.metres && !raw.units.metres && metres.grid == raw.grid);
        let base = of("base");
        assert!(base.view.behind + base.view.beyond_any_view > base.valid / 2, "{:?}", base.view);
        assert!(raw.view.behind == 0 && raw.view.beyond_any_view == 0);
        // Downsampled or cropped: measured from the cloud's own spacing.
        for text in ["voxel:1", "cropped:25,voxel:1,metres"] {
            let measured = of(text);
            let spacing = measured.spacing_mm.unwrap();
            assert!(measured.measured_density && measured.grid.is_none(), "{text}");
            assert!((0.7..1.4).contains(&spacing) && measured.radius_mm > raw.radius_mm, "{text}: {spacing} mm");
        }
        assert!(of("cropped:25").valid < raw.valid / 4);
    }
}
