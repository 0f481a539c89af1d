//! The frame's grid before the stages run: an unorganized cloud that is a
//! raw camera export which lost its grid is put back on the camera's pixel
//! grid ([`regrid`]), so it plans as the organized frame it was, at the
//! same speed; an organized frame's own pinhole is estimated
//! ([`crate::camera::estimate_intrinsics`]) and checked against the
//! configured camera, or stands in for it when the frame is another
//! camera's. [`prepare`] makes those decisions for `Planner::plan` and
//! logs them.
//!
//! A raw frame shows itself when projected through the intrinsics: each
//! point lands on its own pixel, within a rounding error of the pixel's
//! centre, and the occupied pixels fill most of their bounding box with
//! neighbours along both axes. A voxel-downsampled cloud (centroids fall
//! anywhere in a pixel), a merged one (views share pixels), a decimated
//! one (every other pixel) or another camera's (off the pixel centres)
//! fails one of those tests and keeps the unorganized path, with the
//! reason logged.

use std::borrow::Cow;
use std::fmt;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use crate::camera::{CameraModel, Intrinsics, estimate_intrinsics};
use crate::cloud::{INVALID_POINT, PointCloud};
use crate::geometry::Vec3;

/// How far from a pixel centre a raw frame's point may project, pixels.
/// The camera computed each point on its pixel's ray, so only the f32
/// rounding of the coordinates (about 1e-4 px on a 2 k sensor) and the
/// rounding of datasheet intrinsics (hundredths of a pixel) move it; a
/// resampled point lands anywhere, within this of a centre along both
/// axes only 4% of the time.
pub const PIXEL_CENTRE_TOLERANCE_PX: f64 = 0.1;

/// The largest fraction of points that may miss their pixel (off its
/// centre or off the sensor) in a cloud still taken for a raw frame:
/// nearly all must land, a few stray ones (a point edited by a filter) are
/// dropped.
pub const MAX_MISFIT_FRACTION: f64 = 0.01;

/// The largest fraction of points that may share a pixel with another: a
/// raw frame has one point per pixel, so any more is merged views or a
/// resampled cloud. The nearer point of a pair is kept.
pub const MAX_COLLISION_FRACTION: f64 = 0.005;

/// The least fraction of their bounding box the occupied pixels must
/// cover. A raw frame of a workpiece covers most of it (holes are shadows
/// and dark patches); a cloud sampled every second pixel both ways covers
/// a quarter.
pub const MIN_COVERAGE: f64 = 0.3;

/// The least fraction of occupied pixels with an occupied neighbour both
/// along the row and along the column. A raw frame's surfaces are solid
/// patches of pixels; a cloud decimated along one axis has no pixel with
/// a neighbour along it.
pub const MIN_PAIRED_FRACTION: f64 = 0.5;

/// How far an organized frame's estimated focal lengths may stray from the
/// configured ones, as a fraction. Calibrations of one camera agree to a
/// tenth of a percent; beyond half a percent the config describes another
/// camera (or a wrong one), and every expected neighbour count, which goes
/// with `fx fy` (Eq. 4), is off by a percent or more.
pub const FOCAL_TOLERANCE: f64 = 0.005;

/// How far an organized frame's estimated principal point may stray from
/// the configured one, pixels: well above the estimate's own noise, and
/// about where an off-centre principal point starts to move the view's
/// edges, which the lap seam's ends are clipped against.
pub const PRINCIPAL_POINT_TOLERANCE_PX: f64 = 2.0;

/// The largest RMS residual, pixels, of an estimate that is used in place
/// of the configured camera: a pinhole frame fits to a thousandth of a
/// pixel; beyond half a pixel the grid is not a pinhole camera's (strong
/// distortion, a resampled or synthetic grid) and the estimate means little.
pub const MAX_PINHOLE_RESIDUAL_PX: f64 = 0.5;

/// Why an unorganized cloud was not put back on the camera's grid.
#[derive(Debug, Clone, PartialEq)]
pub enum NotARawFrame {
    /// No point, or more points than the sensor has pixels.
    Size { points: usize, pixels: usize },
    /// Too many points project off a pixel centre or off the sensor.
    OffGrid { off_centre: usize, outside: usize, points: usize },
    /// Too many points share a pixel.
    Collisions { collisions: usize, points: usize },
    /// The occupied pixels are too sparse in their bounding box.
    Sparse { coverage: f64 },
    /// Too few occupied pixels have neighbours along both axes.
    Scattered { paired: f64 },
}

impl fmt::Display for NotARawFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
        match *self {
            NotARawFrame::Size { points, pixels } => {
                write!(f, "{points} points for a sensor of {pixels} pixels")
            }
            NotARawFrame::OffGrid { off_centre, outside, points } => write!(
                f,
                "{:.1}% of the points project off a pixel centre (beyond {PIXEL_CENTRE_TOLERANCE_PX} px) and \
                 {:.1}% outside the sensor, more than {}% of a raw frame's: downsampled, filtered, another \
                 camera's or not in the camera frame",
                pct(off_centre, points),
                pct(outside, points),
                MAX_MISFIT_FRACTION * 100.0
            ),
            NotARawFrame::Collisions { collisions, points } => write!(
                f,
                "{:.2}% of the points share a pixel with another, more than {}%: merged views or resampled",
                pct(collisions, points),
                MAX_COLLISION_FRACTION * 100.0
            ),
            NotARawFrame::Sparse { coverage } => write!(
                f,
                "the occupied pixels cover {:.0}% of their bounding box, less than {:.0}%: decimated",
                coverage * 100.0,
                MIN_COVERAGE * 100.0
            ),
            NotARawFrame::Scattered { paired } => write!(
                f,
                "{:.0}% of the occupied pixels have neighbours along both image axes, less than {:.0}%: decimated",
                paired * 100.0,
                MIN_PAIRED_FRACTION * 100.0
            ),
        }
    }
}

/// What a re-gridding did, for the log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Regridded {
    /// Points placed on their pixel.
    pub placed: usize,
    /// Points dropped: off their pixel, or the farther of a pair.
    pub dropped: usize,
    pub coverage: f64,
}

/// Where a point projects: its pixel, or why none.
const OFF_CENTRE: u32 = u32::MAX;
const OUTSIDE: u32 = u32::MAX - 1;

/// A pixel no point has landed on. No point has this index: a cloud has
/// at most as many points as the sensor has pixels, and pixel numbers
/// stop short of [`OUTSIDE`].
const EMPTY_SLOT: u32 = u32::MAX;

/// Puts the points of an unorganized camera-frame cloud back on `camera`'s
/// pixel grid, each on the pixel it projects to (through the distortion,
/// if any), when the projection is that of a raw frame of this camera (see
/// the module doc and the tolerances above); the other pixels are invalid.
/// Otherwise says why the cloud is not a raw frame. Runs on rayon; the
/// result does not depend on the points' order or the thread count.
pub fn regrid(cloud: &PointCloud, camera: &CameraModel) -> Result<(PointCloud, Regridded), NotARawFrame> {
    let (width, height) = (camera.width_px as usize, camera.height_px as usize);
    let points = cloud.points();
    let n = points.len();
    if n == 0 || n > width * height {
        return Err(NotARawFrame::Size { points: n, pixels: width * height });
    }
    let pixel_of = |p: &[f32; 3]| -> u32 {
        let Some((u, v)) = camera.project(&Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64)) else {
            return OUTSIDE;
        };
        let (col, row) = (u.round(), v.round());
        if !(col >= 0.0 && row >= 0.0 && col < width as f64 && row < height as f64) {
            return OUTSIDE;
        }
        if (u - col).abs() > PIXEL_CENTRE_TOLERANCE_PX || (v - row).abs() > PIXEL_CENTRE_TOLERANCE_PX {
            return OFF_CENTRE;
        }
        (row as usize * width + col as usize) as u32
    };
    let pixels: Vec<u32> = points.par_iter().map(pixel_of).collect();
    let (off_centre, outside) = pixels
        .par_iter()
        .map(|&k| ((k == OFF_CENTRE) as usize, (k == OUTSIDE) as usize))
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    if (off_centre + outside) as f64 > MAX_MISFIT_FRACTION * n as f64 {
        return Err(NotARawFrame::OffGrid { off_centre, outside, points: n });
    }
    // Each pixel keeps its nearest point: the least key, the depth's bits
    // (positive floats order as their bits) above the index, so the choice
    // is the same whatever order the points come in. A slot holds the
    // index alone (half a 64-bit key's memory over the sensor, 9 MB at
    // 2.3 MP), and the key is made again to compare.
    let key_of = |i: u32| (u64::from(points[i as usize][2].to_bits()) << 32) | u64::from(i);
    let slots: Vec<AtomicU32> = (0..width * height).into_par_iter().map(|_| AtomicU32::new(EMPTY_SLOT)).collect();
    let collisions: usize = pixels
        .par_iter()
        .enumerate()
        .filter(|(_, k)| **k < OUTSIDE)
        .map(|(i, &k)| {
            let (i, slot) = (i as u32, &slots[k as usize]);
            // Exactly one point of a pixel finds it empty: the others
            // are its collisions, whichever of them comes first.
            let mut held = slot.load(Ordering::Relaxed);
            while held == EMPTY_SLOT || key_of(i) < key_of(held) {
                match slot.compare_exchange_weak(held, i, Ordering::Relaxed, Ordering::Relaxed) {
                    Ok(_) => break,
                    Err(now) => held = now,
                }
            }
            (held != EMPTY_SLOT) as usize
        })
        .sum();
    if collisions as f64 > MAX_COLLISION_FRACTION * n as f64 {
        return Err(NotARawFrame::Collisions { collisions, points: n });
    }
    drop(pixels);
    let occupied = |k: usize| slots[k].load(Ordering::Relaxed) != EMPTY_SLOT;
    // Per row: occupied pixels, those with neighbours along both axes, and
    // the occupied columns' extent; rows merged in order.
    let rows: Vec<(usize, usize, usize, usize)> = (0..height)
        .into_par_iter()
        .map(|row| {
            let (mut count, mut paired, mut lo, mut hi) = (0, 0, usize::MAX, 0);
            for col in 0..width {
                let k = row * width + col;
                if !occupied(k) {
                    continue;
                }
                count += 1;
                lo = lo.min(col);
                hi = hi.max(col);
                let along_row = (col > 0 && occupied(k - 1)) || (col + 1 < width && occupied(k + 1));
                let along_col = (row > 0 && occupied(k - width)) || (row + 1 < height && occupied(k + width));
                paired += (along_row && along_col) as usize;
            }
            (count, paired, lo, hi)
        })
        .collect();
    let placed: usize = rows.iter().map(|r| r.0).sum();
    let paired: usize = rows.iter().map(|r| r.1).sum();
    let (Some(first_row), Some(last_row)) = (rows.iter().position(|r| r.0 > 0), rows.iter().rposition(|r| r.0 > 0))
    else {
        return Err(NotARawFrame::Size { points: n, pixels: width * height });
    };
    let first_col = rows.iter().map(|r| r.2).min().unwrap_or(0);
    let last_col = rows.iter().filter(|r| r.0 > 0).map(|r| r.3).max().unwrap_or(0);
    let bounding_box = (last_row - first_row + 1) * (last_col - first_col + 1);
    let coverage = placed as f64 / bounding_box as f64;
    if coverage < MIN_COVERAGE {
        return Err(NotARawFrame::Sparse { coverage });
    }
    let paired = paired as f64 / placed as f64;
    if paired < MIN_PAIRED_FRACTION {
        return Err(NotARawFrame::Scattered { paired });
    }
    let grid: Vec<[f32; 3]> = slots
        .par_iter()
        .map(|s| match s.load(Ordering::Relaxed) {
            EMPTY_SLOT => INVALID_POINT,
            i => points[i as usize],
        })
        .collect();
    let cloud = PointCloud::organized(width, height, grid).expect("the grid has the sensor's size");
    Ok((cloud, Regridded { placed, dropped: n - placed, coverage }))
}

/// The frame the stages run on, and the camera they run with when it is
/// not the configured one.
pub(super) struct Prepared<'a> {
    pub cloud: Cow<'a, PointCloud>,
    pub camera: Option<CameraModel>,
}

/// The planner's one step before the stages: re-grid a raw export, check
/// an organized frame's pinhole against the config, or take it in place of
/// the config for another camera's frame. Logs what it decided and why.
/// A re-gridded cloud is dropped as soon as its grid is made, so a cloud
/// the planner owns is not held beside it.
pub(super) fn prepare<'a>(camera: &CameraModel, cloud: Cow<'a, PointCloud>) -> Prepared<'a> {
    let keep = |cloud: Cow<'a, PointCloud>| Prepared { cloud, camera: None };
    if !cloud.is_organized() {
        let start = Instant::now();
        return match regrid(&cloud, camera) {
            Ok((grid, done)) => {
                tracing::info!(
                    placed = done.placed,
                    dropped = done.dropped,
                    coverage = done.coverage,
                    ms = start.elapsed().as_secs_f64() * 1e3,
                    "the unorganized cloud is a raw {}x{} frame without its grid: planned on that grid",
                    camera.width_px,
                    camera.height_px
                );
                Prepared { cloud: Cow::Owned(grid), camera: None }
            }
            Err(why) => {
                tracing::info!(points = cloud.len(), "the unorganized cloud is planned without a grid: {why}");
                keep(cloud)
            }
        };
    }
    let Some(estimate) = estimate_intrinsics(&cloud) else {
        return keep(cloud);
    };
    let (e, c) = (estimate.intrinsics, camera.pinhole());
    let focal_agrees =
        ((e.fx - c.fx) / c.fx).abs() <= FOCAL_TOLERANCE && ((e.fy - c.fy) / c.fy).abs() <= FOCAL_TOLERANCE;
    let own_size = (cloud.width(), cloud.height()) == (camera.width_px as usize, camera.height_px as usize);
    let pinhole_fit = estimate.rms_residual_px.iter().all(|r| *r <= MAX_PINHOLE_RESIDUAL_PX);
    let shown = |i: &Intrinsics| format!("fx {:.2} fy {:.2} cx {:.2} cy {:.2}", i.fx, i.fy, i.cx, i.cy);
    if !camera.distortion.is_none() {
        // The linear fit holds for a pinhole: a distorted frame's
        // estimate is only roughly its focal length.
        tracing::debug!(estimate = %shown(&e), "estimated intrinsics not compared: the camera has distortion");
        return keep(cloud);
    }
    if own_size {
        let centre_agrees =
            (e.cx - c.cx).abs() <= PRINCIPAL_POINT_TOLERANCE_PX && (e.cy - c.cy).abs() <= PRINCIPAL_POINT_TOLERANCE_PX;
        if !(focal_agrees && centre_agrees) {
            tracing::warn!(
                estimate = %shown(&e),
                configured = %shown(&c),
                rms_residual_px = ?estimate.rms_residual_px,
                "the frame's own intrinsics disagree with [camera] (beyond {}% focal, {} px centre): \
                 configure the camera's fx, fy, cx, cy",
                FOCAL_TOLERANCE * 100.0,
                PRINCIPAL_POINT_TOLERANCE_PX
            );
        }
        return keep(cloud);
    }
    if focal_agrees {
        tracing::debug!(estimate = %shown(&e), "a {}x{} crop of the configured camera", cloud.width(), cloud.height());
        return keep(cloud);
    }
    // Beyond 32768 pixels a side the full-plane counts' 16-bit tile keys
    // would not hold the frame as a camera's own.
    let sensor_sized = cloud.width() <= 1 << 15 && cloud.height() <= 1 << 15;
    if !(pinhole_fit && sensor_sized && e.fx > 0.0 && e.fy > 0.0) {
        tracing::warn!(
            estimate = %shown(&e),
            rms_residual_px = ?estimate.rms_residual_px,
            "a {}x{} frame not of the configured camera, and no pinhole fits it (mirrored or resampled?): \
             planned with [camera]",
            cloud.width(),
            cloud.height()
        );
        return keep(cloud);
    }
    tracing::info!(
        estimate = %shown(&e),
        configured = %shown(&c),
        "a {}x{} frame of another camera than [camera]: planned with its estimated intrinsics",
        cloud.width(),
        cloud.height()
    );
    let other = camera.with_pinhole(cloud.width() as u32, cloud.height() as u32, e);
    Prepared { cloud, camera: Some(other) }
}
