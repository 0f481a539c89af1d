//! V-grooves that end in a flat root land ([`root_land_suite`]): the
//! bevels run down onto a narrow floor parallel to the plates instead of
//! meeting in a sharp root. A bar with a groove cut into it shows this, and
//! so do two bevelled plates over a backing bar seen through their root
//! gap; from the camera the two are the same surfaces. The scene is built
//! as the second: bevels cut through the whole plate, a root gap as wide
//! as the land, the plates lying on the table (on shims a twentieth of a
//! millimetre thick, [`LAND_SHIM_MM`]) whose top is the land. The root
//! the truth names is the centre of the land at its height.
//!
//! The plates fill the view, so the land is the only surface seen behind
//! them: the planner must take it for the groove's own floor, not for
//! what the plates rest on, and measure the groove's depth down to it.
//! Seeded like the other suites, with `-holdout` scenes from their own
//! seed that nothing in the planner is to be tuned on.

use rand_chacha::ChaCha8Rng;

use super::draw::Draw;
use super::suite::{ScenePlan, uniform};
use super::{JointGeometry, SceneSpec};
use crate::camera::CameraModel;
use crate::joint::JointType;

/// Scenes of [`root_land_suite`], and how many of them (the last) are held
/// out.
pub const ROOT_LAND_SCENES: usize = 12;
pub const ROOT_LAND_HOLDOUT: usize = 4;
const ROOT_LAND_SEED: u64 = 0x1a4d_2026;
const ROOT_LAND_HOLDOUT_SEED: u64 = 0x1a4d_0ff5;

/// The tilt range of the eval suite's strata the scenes take.
const MAX_TILT_DEG: f64 = 30.0;
/// The framings of the eval suite's plan that fill the view (its first
/// four scenes): the scenes take them in turn.
const FILL_PLANS: usize = 4;

/// The plates' thickness (the groove runs through it), mm.
const THICKNESS_MM: [f64; 2] = [6.0, 12.0];
/// The groove's full angle, degrees: bevels of 30 to 50 degrees a side.
const GROOVE_ANGLE_DEG: [f64; 2] = [60.0, 100.0];
/// The land's width, mm, and the most it may take of the groove's opening:
/// a root land is narrow beside the groove (issue 49's bar: 6 to 10 mm of
/// a groove 30 mm wide).
const LAND_MM: [f64; 2] = [2.5, 8.0];
const MAX_LAND_SHARE: f64 = 0.4;
/// The spacers' height under the plates, mm: the table is the land, so the
/// plates lie on it; a spacer must have some height.
pub const LAND_SHIM_MM: f64 = 0.05;

/// The root-land scenes, named like `root-land-07-d548-t14-l4.2` (index,
/// standoff, tilt, land width); the last [`ROOT_LAND_HOLDOUT`] are
/// `-holdout`. Each takes the standoff, tilt and framing of one of the
/// eval suite's V-butt scenes that fill the view (no table in sight beside
/// the plates), and draws its cross-section as the module says.
pub fn root_land_suite(draw: Draw) -> Vec<(String, SceneSpec)> {
    let camera = CameraModel::default();
    (0..ROOT_LAND_SCENES)
        .map(|k| {
            let plan = ScenePlan::new(JointType::VButt, 0, k % FILL_PLANS, MAX_TILT_DEG);
            debug_assert!(plan.fills_view());
            let holdout = k >= ROOT_LAND_SCENES - ROOT_LAND_HOLDOUT;
            let base_seed = draw.seed(if holdout { ROOT_LAND_HOLDOUT_SEED } else { ROOT_LAND_SEED });
            let spec = plan.draw_framed_reshaped(base_seed, k as u64, &camera, reshape_to_land);
            let land = match spec.joint {
                JointGeometry::VButt { root_gap_mm, .. } => root_gap_mm,
                _ => 0.0,
            };
            let (distance, tilt) = (spec.placement.distance_mm, spec.placement.tilt_deg);
            (format!("root-land-{k:02}-d{distance:.0}-t{tilt:.0}-l{land:.1}{}", draw.suffix(holdout)), spec)
        })
        .collect()
}

/// The drawn V-butt scene made a groove with a root land.
pub(super) fn reshape_to_land(spec: &mut SceneSpec, rng: &mut ChaCha8Rng) {
    let thickness = uniform(rng, THICKNESS_MM[0], THICKNESS_MM[1]);
    let angle = uniform(rng, GROOVE_ANGLE_DEG[0], GROOVE_ANGLE_DEG[1]);
    let opening_without_land = 2.0 * thickness * (angle / 2.0).to_radians().tan();
    // land <= share (land + run): land <= share run / (1 - share).
    let widest = (MAX_LAND_SHARE * opening_without_land / (1.0 - MAX_LAND_SHARE)).min(LAND_MM[1]);
    let land = uniform(rng, LAND_MM[0], widest.max(LAND_MM[0]));
    spec.joint = JointGeometry::VButt {
        thickness_mm: thickness,
        groove_angle_deg: angle,
        groove_depth_mm: thickness,
        root_gap_mm: land,
    };
    spec.spacer_height_mm = LAND_SHIM_MM;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_root_land_scenes_are_fixed_framed_and_narrow_beside_their_groove() {
        let suite = root_land_suite(Draw::Documented);
        assert_eq!(suite.len(), ROOT_LAND_SCENES);
        assert_eq!(suite.iter().filter(|(n, _)| n.ends_with("-holdout")).count(), ROOT_LAND_HOLDOUT);
        let again = root_land_suite(Draw::Documented);
        for ((name, spec), (other, same)) in suite.iter().zip(&again) {
            assert_eq!(name, other);
            assert_eq!(spec.joint, same.joint, "{name}");
            spec.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
            let JointGeometry::VButt { thickness_mm, groove_depth_mm, root_gap_mm, .. } = spec.joint else {
                panic!("{name}: not a V-groove");
            };
            assert_eq!(groove_depth_mm, thickness_mm, "{name}: the bevels run down to the land");
            let opening = 2.0 * spec.joint.seam_edge_half_width();
            assert!(root_gap_mm >= LAND_MM[0] && root_gap_mm <= MAX_LAND_SHARE * opening + 1e-9, "{name}");
        }
    }
}
