//! The robust plane criterion's block kernels (depth range, normal test)
//! give the bits of their scalar forms on every instruction set
//! level this CPU runs, forced in turn, on crops of realistic simulated
//! frames strewn with invalid and extreme points. (That the pipeline's
//! grid paths classify as the KD-tree references do on every level is
//! checked beside them, in src/pipeline/grid_exactness.rs, with the memo
//! keys on the scales the full count uses.)

use super::{BLOCK, Isa, Planes, on_every_isa, scalar};
use crate::camera::CameraModel;
use crate::cloud::PointCloud;
use crate::joint::JointType;
use crate::sim::{demo_scene, simulate};

/// A `w x h` window of a simulated frame centred on the seam's start.
pub(crate) fn crop(joint: JointType, distance_mm: f64, tilt_deg: f64, w: usize, h: usize) -> PointCloud {
    let camera = CameraModel::default();
    let mut spec = demo_scene(joint);
    spec.placement.distance_mm = distance_mm;
    spec.placement.tilt_deg = tilt_deg;
    let sim = simulate(&spec, &camera);
    let s = sim.truth.start_camera;
    let (u, v) = camera.project(&s).expect("the seam start is in front of the camera");
    let c0 = (u as usize).saturating_sub(w / 2).min(camera.width_px as usize - w);
    let r0 = (v as usize).saturating_sub(h / 2).min(camera.height_px as usize - h);
    let full = sim.cloud.points();
    let points = (r0..r0 + h).flat_map(|r| full[r * sim.cloud.width() + c0..][..w].to_vec()).collect();
    PointCloud::organized(w, h, points).expect("crop")
}

/// A crop of a simulated frame with noise, dropouts, a far point and
/// infinities strewn over it, so that every lane test meets finite,
/// invalid and extreme inputs.
fn corrupted_crop(w: usize, h: usize) -> PointCloud {
    let clean = crop(JointType::VButt, 530.0, 15.0, w, h);
    let mut points = clean.points().to_vec();
    for (i, p) in points.iter_mut().enumerate() {
        p[2] += ((i * 7919) % 13) as f32 * 0.01;
        match i % 97 {
            5 => *p = [f32::NAN; 3],
            17 => p[2] = 1.0e30,
            29 => p[0] = f32::INFINITY,
            41 => p[1] = f32::NEG_INFINITY,
            _ => {}
        }
    }
    PointCloud::organized(w, h, points).expect("crop")
}

/// Results of `compute` on every level this CPU runs, each compared with
/// the scalar level's, item by item.
pub(crate) fn agree_with_scalar<T: PartialEq + std::fmt::Debug>(what: &str, compute: impl Fn() -> Vec<T>) -> Vec<T> {
    let (ran, _skipped) = on_every_isa(|_| compute());
    let (first, scalar) = &ran[0];
    assert_eq!(*first, Isa::Scalar);
    for (isa, got) in &ran[1..] {
        assert_eq!(got.len(), scalar.len());
        for (k, (got, want)) in got.iter().zip(scalar).enumerate() {
            assert_eq!(got, want, "{what} of item {k} on {isa:?}");
        }
    }
    ran.into_iter().next().expect("the scalar level always runs").1
}

#[test]
fn the_normal_test_of_every_level_equals_the_scalar_form() {
    let cloud = corrupted_crop(96, 64);
    let (w, h) = (cloud.width(), cloud.height());
    let points = cloud.points();
    let coordinate = |axis: usize| -> Vec<f32> { points.iter().map(|p| p[axis]).collect() };
    let (xs, ys, zs) = (coordinate(0), coordinate(1), coordinate(2));
    let planes = Planes { xs: &xs, ys: &ys, zs: &zs };
    let blocks: Vec<(usize, usize)> = (1..=4)
        .flat_map(|step| {
            (step..h - step)
                .flat_map(move |row| (step..w - BLOCK - step).step_by(3).map(move |col| (row * w + col, step)))
        })
        .collect();
    assert!(blocks.len() > 5000);
    // Tilted references and cones wide and narrow, so both answers occur.
    let tests = [([0.26f32, 0.0, 0.966], 0.883f32), ([0.0, 0.0, 1.0], 0.99), ([-0.6, 0.3, 0.74], 0.5)];
    let masks = agree_with_scalar("normal test", || {
        tests
            .iter()
            .flat_map(|&(reference, cos_sq)| {
                let test = super::NormalTest { reference, cos_sq };
                blocks.iter().map(move |&(first, step)| super::normal_test(planes, w, first, step, &test))
            })
            .collect()
    });
    let scalar_masks: Vec<_> = tests
        .iter()
        .flat_map(|&(reference, cos_sq)| {
            let test = super::NormalTest { reference, cos_sq };
            blocks.iter().map(move |&(first, step)| scalar::normal_test(planes, w, first, step, &test))
        })
        .collect();
    assert_eq!(masks, scalar_masks, "the scalar level runs the scalar form");
    let lanes = |f: fn(&super::LaneMasks) -> u32| masks.iter().map(|m| f(m).count_ones() as usize).sum::<usize>();
    let (complete, facing) = (lanes(|m| m.complete), lanes(|m| m.complete & m.facing));
    let all = masks.len() * BLOCK;
    assert!(complete < all && facing < complete && facing > 0, "{facing} facing of {complete} complete of {all}");
}

#[test]
fn the_depth_range_of_every_level_equals_the_scalar_form() {
    // Every pattern of invalid lanes among eight, over depths that tie,
    // ascend, descend and include infinities.
    let depths = [480.0f32, 480.0, 512.25, 1.0e30, f32::INFINITY, 499.999, 700.0, 480.000_03];
    let blocks: Vec<[f32; BLOCK]> = (0u32..256)
        .flat_map(|invalid| {
            (0..3).map(move |shift| {
                std::array::from_fn(|l| if invalid >> l & 1 == 1 { f32::NAN } else { depths[(l + shift * 3) % BLOCK] })
            })
        })
        .collect();
    let ranges = agree_with_scalar("depth range", || blocks.iter().map(super::depth_range).collect());
    for (z, range) in blocks.iter().zip(&ranges) {
        let valid: Vec<f32> = z.iter().copied().filter(|v| !v.is_nan()).collect();
        let expected = (
            valid.iter().copied().fold(f32::INFINITY, f32::min),
            valid.iter().copied().fold(f32::NEG_INFINITY, f32::max),
        );
        assert_eq!(*range, expected, "{z:?}");
    }
}
