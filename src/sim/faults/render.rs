//! What each fault puts into the frame: the solids the scene renders
//! (clamps, tacks, spatter, a touching part), the bands and runs of
//! missing depth (dropouts, glaring edges), the streaks drawn after the
//! sensor noise, and the placement that brings a seam barely into view.

use super::*;

/// The solids the faults add to the scene, in the workpiece frame.
pub fn fault_solids(spec: &SceneSpec) -> Vec<ConvexSolid> {
    let mut solids = Vec::new();
    for fault in &spec.faults {
        match *fault {
            Fault::Clamp { centre_mm, width_mm, height_mm, half_reach_mm } => {
                let top = spec.joint.top_z(-1.0).max(spec.joint.top_z(1.0));
                solids.extend(ConvexSolid::cuboid(
                    SurfaceKind::Clutter,
                    Vec3::new(-half_reach_mm, centre_mm - width_mm / 2.0, top),
                    Vec3::new(half_reach_mm, centre_mm + width_mm / 2.0, top + height_mm),
                ));
            }
            Fault::TackWelds { first_mm, pitch_mm, length_mm, crown_mm, spread_mm } => {
                let profile = tack_profile(&spec.joint, crown_mm, spread_mm);
                let [y0, y1] = spec.seam_range();
                let mut centre = first_mm;
                while centre - length_mm / 2.0 < y1 {
                    let span = [(centre - length_mm / 2.0).max(y0), (centre + length_mm / 2.0).min(y1)];
                    solids.extend(ConvexSolid::extruded(SurfaceKind::Weld, &profile, span));
                    centre += pitch_mm;
                }
            }
            Fault::Spatter { seed, count, radius_mm, spread_mm } => {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                rng.set_stream(FaultKind::Spatter as u64);
                let [y0, y1] = spec.seam_range();
                let nearest = spec.joint.seam_edge_half_width() + radius_mm;
                for _ in 0..count {
                    let side = if rng.next_u32().is_multiple_of(2) { -1.0 } else { 1.0 };
                    let x = side * uniform(&mut rng, nearest, spread_mm);
                    let y = uniform(&mut rng, y0, y1);
                    let z = spec.joint.top_z(x);
                    let octagon: Vec<[f64; 2]> = (0..BEAD_CORNERS)
                        .map(|k| {
                            let a = std::f64::consts::TAU * k as f64 / BEAD_CORNERS as f64;
                            [x + radius_mm * a.cos(), z + radius_mm * a.sin()]
                        })
                        .collect();
                    solids.extend(ConvexSolid::extruded(SurfaceKind::Weld, &octagon, [y - radius_mm, y + radius_mm]));
                }
            }
            Fault::TouchingPart { plate, width_mm, step_mm } => {
                let [top, bottom] = plate_top_and_bottom(&spec.joint, plate);
                let (extent, x0, x1) = match plate {
                    PlateSide::A => (&spec.plate_a, -spec.plate_a.width_mm - width_mm, -spec.plate_a.width_mm),
                    PlateSide::B => (&spec.plate_b, spec.plate_b.width_mm, spec.plate_b.width_mm + width_mm),
                };
                solids.extend(ConvexSolid::cuboid(
                    SurfaceKind::Plate,
                    Vec3::new(x0, extent.offset_mm, bottom),
                    Vec3::new(x1, extent.offset_mm + extent.length_mm, top + step_mm),
                ));
            }
            Fault::WrongJoint { .. }
            | Fault::SeamDropout { .. }
            | Fault::SpecularStreaks { .. }
            | Fault::BarelyInView { .. }
            | Fault::EdgeGlare { .. } => {}
        }
    }
    solids
}

/// A tack's cross-section (convex, in xz): it fills the gap or the groove
/// from its root up and crowns above the top, `spread` wider than the
/// opening either side; for a lap, a fillet in the corner.
fn tack_profile(joint: &JointGeometry, crown: f64, spread: f64) -> Vec<[f64; 2]> {
    let crowned = |bottom: [[f64; 2]; 2], top_z: f64, half_top: f64| {
        vec![
            bottom[0],
            bottom[1],
            [half_top, top_z],
            [0.5 * half_top, top_z + crown],
            [-0.5 * half_top, top_z + crown],
            [-half_top, top_z],
        ]
    };
    match *joint {
        JointGeometry::IButt { thickness_mm: t, gap_mm } => {
            let h = gap_mm / 2.0;
            crowned([[-h, 0.0], [h, 0.0]], t, h + spread)
        }
        JointGeometry::VButt { thickness_mm: t, groove_depth_mm: d, root_gap_mm: r, .. } => {
            let top = joint.seam_edge_half_width() + spread;
            crowned([[-r / 2.0, t - d], [r / 2.0, t - d]], t, top)
        }
        JointGeometry::Lap { lower_thickness_mm: t1, upper_thickness_mm: t2, .. } => {
            let leg = spread + crown;
            vec![[-0.5, t1], [leg, t1], [-0.5, t1 + leg.min(t2)]]
        }
        // A tack in the -x root's corner (faults are not drawn on tees yet:
        // [`Fault::validate`] refuses them; this keeps the profile total).
        JointGeometry::Tee { flange_thickness_mm: f, web_thickness_mm: w, web_height_mm: h } => {
            let (leg, root) = (spread + crown, -w / 2.0);
            vec![[root + 0.5, f], [root - leg, f], [root + 0.5, f + leg.min(h)]]
        }
        // A tack on the corner's weld line (refused on corners likewise).
        JointGeometry::Corner { flange_thickness_mm: f, .. } => {
            let leg = spread + crown;
            vec![[-0.5, f], [leg, f], [-0.5, f + leg]]
        }
    }
}

/// Removes from noise-free depths (row-major, camera frame) the returns of
/// the dropout bands and of the glaring edges' runs; nothing changes
/// without such a fault.
pub fn erase_dropout_bands(depths: &mut [f64], spec: &SceneSpec, camera: &CameraModel) {
    let bands: Vec<([f64; 2], f64)> = spec
        .faults
        .iter()
        .filter_map(|f| match *f {
            Fault::SeamDropout { along_mm, margin_mm } => {
                Some((along_mm, spec.joint.seam_edge_half_width() + margin_mm))
            }
            _ => None,
        })
        .collect();
    // Each glaring edge as its point in xz, the glare's reach about it and
    // the runs along the seam where it glares.
    let edges = spec.joint.seam_edges_xz();
    let glare: Vec<([f64; 2], f64, Vec<[f64; 2]>)> = spec
        .faults
        .iter()
        .filter_map(|f| match *f {
            Fault::EdgeGlare { band_mm, .. } => Some((band_mm, f.glare_runs(spec))),
            _ => None,
        })
        .flat_map(|(band, runs)| edges.into_iter().zip(runs).map(move |(edge, runs)| (edge, band, runs)))
        .collect();
    if bands.is_empty() && glare.is_empty() {
        return;
    }
    let erased = |w: &Vec3| {
        bands.iter().any(|([a, b], half)| (*a..=*b).contains(&w.y) && w.x.abs() <= *half)
            || glare.iter().any(|([x, z], band, runs)| {
                (w.x - x).hypot(w.z - z) <= *band && runs.iter().any(|[a, b]| (*a..=*b).contains(&w.y))
            })
    };
    let workpiece_from_camera = spec.workpiece_from_camera();
    let width = (camera.width_px as usize).max(1);
    depths.par_chunks_mut(width).enumerate().for_each(|(row, out)| {
        for (col, z) in out.iter_mut().enumerate() {
            if !z.is_finite() {
                continue;
            }
            let [rx, ry, _] = camera.ray(col as f64, row as f64);
            let w = workpiece_from_camera.transform_point(&Vec3::new(rx * *z, ry * *z, *z).into()).coords;
            if erased(&w) {
                *z = f64::NAN;
            }
        }
    });
}

/// Draws the specular streaks into a frame's depths (after the sensor's
/// noise: a streak is the sensor's error, not a surface).
pub fn draw_streaks(depths: &mut [f64], spec: &SceneSpec, camera: &CameraModel) {
    let camera_from_workpiece = spec.workpiece_from_camera().inverse();
    let (width, height) = (camera.width_px as usize, camera.height_px as usize);
    for fault in &spec.faults {
        let Fault::SpecularStreaks { seed, count, length_mm, width_px, offset_mm } = *fault else {
            continue;
        };
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(FaultKind::SpecularStreaks as u64);
        let [y0, y1] = spec.seam_range();
        for _ in 0..count {
            let x = uniform(&mut rng, -20.0, 20.0);
            let y = uniform(&mut rng, y0, y1);
            let angle = uniform(&mut rng, 0.0, std::f64::consts::PI);
            let sign = if rng.next_u32().is_multiple_of(2) { -1.0 } else { 1.0 };
            let half = Vec3::new(angle.cos(), angle.sin(), 0.0) * (length_mm / 2.0);
            let centre = Vec3::new(x, y, spec.joint.top_z(x));
            let ends = [centre - half, centre + half]
                .map(|p| camera.project(&camera_from_workpiece.transform_point(&p.into()).coords));
            let [Some(a), Some(b)] = ends else { continue };
            let reach = width_px / 2.0;
            let (u_lo, u_hi) = (a.0.min(b.0) - reach, a.0.max(b.0) + reach);
            let (v_lo, v_hi) = (a.1.min(b.1) - reach, a.1.max(b.1) + reach);
            let clamp_px = |v: f64, n: usize| v.clamp(0.0, n.saturating_sub(1) as f64) as usize;
            for row in clamp_px(v_lo.floor(), height)..=clamp_px(v_hi.ceil(), height) {
                for col in clamp_px(u_lo.floor(), width)..=clamp_px(u_hi.ceil(), width) {
                    let z = &mut depths[row * width + col];
                    if z.is_finite() && distance_to_segment_px((col as f64, row as f64), a, b) <= reach {
                        let off = sign * offset_mm * (1.0 + 0.5 * uniform(&mut rng, -1.0, 1.0));
                        *z = (*z + off).max(f64::MIN_POSITIVE);
                    }
                }
            }
        }
    }
}

fn distance_to_segment_px(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let length2 = dx * dx + dy * dy;
    let t = if length2 > 0.0 { (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / length2).clamp(0.0, 1.0) } else { 0.0 };
    (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy)
}

/// Sets the camera's aim across the seam so that only `in_view_mm` of the
/// plate a [`Fault::BarelyInView`] names is in view (at the middle of the
/// observed seam); no change without that fault.
pub fn frame_barely_in_view(spec: &mut SceneSpec, camera: &CameraModel) -> Result<(), InvalidScene> {
    let Some((plate, wanted)) = spec.faults.iter().find_map(|f| match *f {
        Fault::BarelyInView { plate, in_view_mm } => Some((plate, in_view_mm)),
        _ => None,
    }) else {
        return Ok(());
    };
    let index = match plate {
        PlateSide::A => 0,
        PlateSide::B => 1,
    };
    let shown = |spec: &SceneSpec, across: f64| -> Option<f64> {
        let mut moved = spec.clone();
        moved.placement.target_offset_mm[0] = across;
        let [y0, y1] = observed_seam_range(&moved, camera)?;
        Some(plates_in_view(&moved, camera, (y0 + y1) / 2.0)[index])
    };
    // Aiming away from the plate shows less of it: walk away until
    // less than wanted shows, then halve the step.
    let away = if index == 0 { 1.0 } else { -1.0 };
    let start = spec.placement.target_offset_mm[0];
    let mut near = start - away * 300.0;
    let mut far = None;
    let mut across = near;
    while (across - start).abs() <= 300.0 {
        match shown(spec, across) {
            Some(w) if w < wanted => {
                far = Some(across);
                break;
            }
            Some(_) => near = across,
            None => {}
        }
        across += away * 2.0;
    }
    let Some(mut far) = far else {
        return Err(InvalidScene(format!("no aim shows only {wanted} mm of plate {plate:?}")));
    };
    for _ in 0..40 {
        let middle = (near + far) / 2.0;
        match shown(spec, middle) {
            Some(w) if w >= wanted => near = middle,
            _ => far = middle,
        }
    }
    spec.placement.target_offset_mm[0] = near;
    Ok(())
}
