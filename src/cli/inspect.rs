//! `weldseam inspect`: what the planner sees in a cloud file, for a person
//! commissioning a camera, as text or as one JSON object on stdout.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context as _;
use serde_json::json;
use weldseam::pipeline::input::{MAX_PLAUSIBLE_FIELD_OF_VIEW_DEG, View};
use weldseam::pipeline::survey::{Survey, survey};

use super::args;

#[derive(Debug, clap::Args)]
pub struct InspectArgs {
    /// Point cloud: .pcd or .ply.
    pub cloud: PathBuf,
    #[command(flatten)]
    pub config: args::ConfigArgs,
    /// Print one JSON object on stdout instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &InspectArgs) -> anyhow::Result<()> {
    let config = args.config.load()?;
    let cloud = weldseam::cloud::load(&args.cloud).with_context(|| format!("cannot read {}", args.cloud.display()))?;
    let seen = survey(&cloud, &config);
    let mut out = std::io::stdout().lock();
    if args.json {
        writeln!(out, "{}", as_json(&seen))?;
    } else {
        write!(out, "{}", as_text(&seen))?;
    }
    Ok(())
}

fn as_json(s: &Survey) -> serde_json::Value {
    json!({
        "points": s.points,
        "valid": s.valid,
        "organized": s.grid.map(|(w, h)| json!({"width": w, "height": h})),
        "units": {"guess": if s.units.metres { "m" } else { "mm" }, "median_distance": s.units.median_distance},
        "depth_mm": s.depth_mm.map(|(near, far)| [near, far]),
        "behind_camera": s.view.behind,
        "beyond_any_view": s.view.beyond_any_view,
        "field_of_view_deg": s.extent.map(|e| json!({"across_x": e.across_x_deg, "across_y": e.across_y_deg})),
        "frame": frame_verdict(s),
        "intrinsics": s.intrinsics.map(|e| json!({
            "fx": e.intrinsics.fx, "fy": e.intrinsics.fy, "cx": e.intrinsics.cx, "cy": e.intrinsics.cy,
            "rms_residual_px": e.rms_residual_px,
        })),
        "regrid": s.regrid.as_ref().map(|r| match r {
            Ok(done) => json!({"raw_frame": true, "placed": done.placed, "coverage": done.coverage}),
            Err(why) => json!({"raw_frame": false, "why": why}),
        }),
        "spacing_mm": s.spacing_mm,
        "spacing_by_depth": s.bands.iter().map(|b| json!({
            "from_mm": b.from_mm, "to_mm": b.to_mm, "points": b.points, "spacing_mm": b.spacing_mm,
        })).collect::<Vec<_>>(),
        "density": if s.measured_density { "measured" } else { "camera" },
        "radius_mm": s.radius_mm,
    })
}

/// Whether the cloud looks like a camera-frame view, in words: the input
/// step's own verdict.
fn frame_verdict(s: &Survey) -> String {
    if s.view.valid == 0 {
        return "no valid point".into();
    }
    let verdict = match s.frame_view() {
        View::Camera => "a camera-frame view",
        View::MostlyBehind => {
            "not a camera-frame view: most points lie behind the camera (a base-frame cloud? plan it with --cloud-frame base)"
        }
        View::MostlyBeyondView => "not a camera-frame view: most points lie beyond any camera's field of view",
        View::WiderThanAnyCamera => {
            let (axis, widest) = s.extent.map_or(("x", f64::NAN), |e| e.widest());
            return format!(
                "not a camera-frame view: seen from the origin its points spread over {widest:.1}° across {axis}, \
                 wider than the {MAX_PLAUSIBLE_FIELD_OF_VIEW_DEG}° any depth camera sees (a base-frame cloud? \
                 plan it with --cloud-frame base and the capture's pose)"
            );
        }
    };
    verdict.into()
}

fn as_text(s: &Survey) -> String {
    let mut t = String::new();
    let line = |t: &mut String, key: &str, value: String| t.push_str(&format!("{key:<20} {value}\n"));
    line(&mut t, "points", format!("{} ({} valid)", s.points, s.valid));
    line(
        &mut t,
        "organized",
        match s.grid {
            Some((w, h)) => format!("yes, {w} x {h}"),
            None => "no".into(),
        },
    );
    line(
        &mut t,
        "units",
        format!(
            "{} (median distance {:.3} in the file's units)",
            if s.units.metres { "metres, guessed" } else { "millimetres, guessed" },
            s.units.median_distance
        ),
    );
    if let Some((near, far)) = s.depth_mm {
        line(&mut t, "depth", format!("{near:.1} to {far:.1} mm"));
    }
    line(&mut t, "frame", frame_verdict(s));
    if let Some(e) = &s.extent {
        line(
            &mut t,
            "field of view",
            format!("{:.1}° across x, {:.1}° across y, seen from the origin", e.across_x_deg, e.across_y_deg),
        );
    }
    if let Some(e) = &s.intrinsics {
        let i = &e.intrinsics;
        line(
            &mut t,
            "intrinsics",
            format!(
                "fx {:.2} fy {:.2} cx {:.2} cy {:.2} px (fit residual {:.3}, {:.3} px)",
                i.fx, i.fy, i.cx, i.cy, e.rms_residual_px[0], e.rms_residual_px[1]
            ),
        );
    }
    match &s.regrid {
        Some(Ok(done)) => line(
            &mut t,
            "grid",
            format!("a raw frame of the configured camera without its grid ({} points placed)", done.placed),
        ),
        Some(Err(why)) => line(&mut t, "grid", format!("none: {why}")),
        None => {}
    }
    match s.spacing_mm {
        Some(sp) => line(&mut t, "spacing", format!("{sp:.3} mm")),
        None => line(&mut t, "spacing", "too sparse to measure".into()),
    }
    for b in &s.bands {
        let spacing = b.spacing_mm.map_or("too sparse".into(), |sp| format!("{sp:.3} mm"));
        line(&mut t, "", format!("{:.0} to {:.0} mm: {} points, spacing {spacing}", b.from_mm, b.to_mm, b.points));
    }
    let rule =
        if s.measured_density { "measured from the cloud's own spacing" } else { "the camera model's (Eq. 4 to 14)" };
    line(&mut t, "plan would use", format!("full-plane counts {rule}, neighbour radius {:.2} mm", s.radius_mm));
    t
}
