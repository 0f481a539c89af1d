//! Under `auto`, the layout the layers do not read: a face standing on the
//! nearest layer of planes, its top out of view, weighed against the butt
//! pair or the lap the layers read once that reading is refused, and read
//! alone where that layer is the lone plane in view ([`on_lone_plane`]).
//!
//! A tee whose web's top is out of view (a tube or a box section standing
//! on a beam, cropped below its top) shows its flange as planes in one
//! layer, often in pieces on both sides of the web, and the web's one side
//! face. The layers see no web's top and read the flange's pieces as a
//! butt pair, or pieces of the table behind as a lap; that reading's edges
//! then fail, as no butt or lap edge is there (the public tube-on-beam
//! scans). Read as a tee, the face's root passes every gate.
//!
//! So both readings are proposed and the evidence picks: the layers'
//! reading where it passes its gates (as before, no plan changes); else
//! the standing face's root where it passes every gate of a tee; else the
//! refusal of whichever reading got further (the later stage), which says
//! most about the cloud (a curved tube's root refused as bending rather
//! than as "no edge line").
//!
//! A fixture's side (a clamp or a bar standing on the plates) stands on
//! them as a web's face does, and its foot is as straight as a root. It is
//! not taken for a web: its top is a plane nearer the camera than the
//! plates, so the nearest layer is the fixture's top and nothing stands on
//! it; where that top is not seen as a plane, the face must still be seen
//! taller than a lap's upper plate is thick (`pipeline.lap_step_max_mm`),
//! the height the layers also ask of a web's top without a request. The
//! fault suite under `auto` (clamps and bars over butt and lap joints)
//! plans exactly as it did without this reading. The rule is
//! [`rules::background::WEB_FACE_WITHOUT_TOP`].
//!
//! Every face of the member standing on the layer ([`web_face::find_all`])
//! is a web's whose top is out of view, each planned as a tee of its own
//! ([`plan_faces`]): a block or a box section shows two faces, and both
//! feet are roots. So it is under `t_fillet` with a lone layer in view,
//! and under `auto` with a lone layer or beside a refused reading of the
//! layers, where every face proposed must stand taller than a lap's upper
//! plate: whether the table behind the flange is in view (a second layer)
//! or cropped away says nothing of what stands on the flange, so the same
//! face is read alike either way.

use crate::geometry::Vec3;
use crate::joint::JointType;
use crate::rules;

use super::super::background::{Layout, PlaneCluster};
use super::super::fillet::Web;
use super::super::web_face::{self, StandingFace};
use super::super::{PlanError, Unplanned, tee};
use super::{Refused, Welds, face_search};
use crate::pipeline::context::Context;

/// The welds of the faces of the member standing on `flange` (the
/// nearest layer of planes; a box section shows two) where the layers'
/// reading as `layout` was `refused` and a face's root passes every gate;
/// else the refusal of the reading that got further.
pub(super) fn instead_of_layers(
    ctx: &mut Context,
    flange: Vec<PlaneCluster>,
    layout: Layout,
    refused: Refused,
) -> Result<Welds, Refused> {
    let pieces: Vec<&PlaneCluster> = flange.iter().collect();
    let search = face_search(ctx, &flange);
    // No valley test here, unlike a lone plane's: with two planes or more
    // in view the groove's flanks lie below its plates' top, where no face
    // is searched, and a web standing square on its flange, seen from above
    // its flange, opens as a groove's flanks may (about 90°). The tee's
    // gates judge the web's angle to its flange.
    let faces = match web_face::find_all(ctx.cloud, &pieces, &search) {
        Ok(faces) => faces,
        Err(why) => {
            tracing::debug!(
                rule = why.rule().id,
                "no face stands on the nearest plane beside the layers' reading: {}",
                why.reason
            );
            return Err(refused);
        }
    };
    // Each face must stand taller than a lap's upper plate: the largest,
    // or nothing is proposed; a further face of the member, or it is left.
    let Some(faces) = taller_than_a_lap(ctx, faces) else { return Err(refused) };
    let lap_step_max_mm = ctx.config.pipeline.lap_step_max_mm;
    let read_as = match layout {
        Layout::Butt => "a butt pair",
        Layout::Lap => "a lap",
        Layout::Tee => "a tee",
    };
    let rule = refused.reason.rule.id;
    let evidence = |face: &StandingFace| {
        let layers = format!(
            "{}, taller than a lap's upper plate ({lap_step_max_mm:.0} mm); the layers read {read_as}, refused by {rule}",
            face_evidence(face, &flange),
        );
        tracing::debug!(rule = rules::background::WEB_FACE_WITHOUT_TOP.id, "{layers}");
        layers
    };
    plan_faces_with(ctx, &faces, &flange, evidence).map_err(|e| further(refused, e, &format!("read as {read_as}")))
}

/// Under `auto` with a lone plane in view (`flange`, the layers reading
/// nothing else: `not_found`), the faces of the member standing on it
/// taller than a lap's upper plate, each planned as a tee whose top is out
/// of view, as beside a refused reading of the layers: the table behind
/// the flange, in view or cropped away, says nothing of what stands on
/// it. Refused by [`rules::background::WEB_FACE_WITHOUT_TOP`] where the
/// largest face is no taller (a fixture's side, a bar), saying what to
/// ask for; by the tee's own rule where its root fails a gate.
pub(super) fn on_lone_plane(
    ctx: &mut Context,
    flange: &[PlaneCluster],
    faces: Vec<StandingFace>,
    not_found: &dyn std::fmt::Display,
) -> Result<Welds, Refused> {
    let lap_step_max_mm = ctx.config.pipeline.lap_step_max_mm;
    let largest = face_evidence(&faces[0], flange);
    let Some(faces) = taller_than_a_lap(ctx, faces) else {
        let reason = format!(
            "{not_found}; {largest}, no taller than a lap's upper plate ({lap_step_max_mm:.0} mm): a fixture's side \
             or a bar may stand so; request t_fillet to plan its root as a tee's"
        );
        return Err(Refused { reason: PlanError::by(&rules::background::WEB_FACE_WITHOUT_TOP, reason), seen: None });
    };
    let evidence = |face: &StandingFace| {
        let layers = format!(
            "{}, taller than a lap's upper plate ({lap_step_max_mm:.0} mm); no other plane is in view",
            face_evidence(face, flange),
        );
        tracing::debug!(rule = rules::background::WEB_FACE_WITHOUT_TOP.id, "{layers}");
        layers
    };
    plan_faces_with(ctx, &faces, flange, evidence).map_err(|reason| Refused { reason, seen: Some(JointType::TFillet) })
}

/// The faces (largest first) that stand taller than a lap's upper plate
/// is thick (`pipeline.lap_step_max_mm`), the height the layers also ask
/// of a web's top without a request; `None` where the largest does not.
/// Each face left out is logged.
fn taller_than_a_lap(ctx: &Context, faces: Vec<StandingFace>) -> Option<Vec<StandingFace>> {
    let lap_step_max_mm = ctx.config.pipeline.lap_step_max_mm;
    let tall = |face: &StandingFace| face.seen_height_mm > lap_step_max_mm;
    for face in faces.iter().filter(|face| !tall(face)) {
        tracing::debug!(
            rule = rules::background::WEB_FACE_WITHOUT_TOP.id,
            seen_height_mm = face.seen_height_mm,
            lap_step_max_mm,
            "a face no taller than a lap's upper plate stands on the nearest plane: a fixture's side, maybe; not proposed"
        );
    }
    if !faces.first().is_some_and(tall) {
        return None;
    }
    Some(faces.into_iter().filter(|face| tall(face)).collect())
}

/// What is seen of a face standing on `flange` with no web's top in view:
/// the evidence a tee read from the face starts with.
pub(super) fn face_evidence(face: &StandingFace, flange: &[PlaneCluster]) -> String {
    format!(
        "no web's top is in view; a side face of {} points stands on the nearest plane ({:.0} mm² in {} piece(s)), \
         seen {:.0} mm tall",
        face.points,
        flange.iter().map(|c| c.area_mm2).sum::<f64>(),
        flange.len(),
        face.seen_height_mm
    )
}

/// The tee a face standing on the flange's pieces makes, its top out of
/// view.
pub(super) fn face_tee<'a>(face: &'a StandingFace, flange_pieces: Vec<&'a PlaneCluster>) -> tee::SeenTee<'a> {
    tee::SeenTee {
        web: Web::Face(face),
        flange_pieces,
        flange_sides: tee::Flange::BothSides,
        depth_to_support_mm: None,
        every_side: false,
    }
}

/// The roots of the faces of a member standing on `flange`, each face a
/// tee of its own whose top is out of view (a block shows two):
/// every root planned, and a face whose tee is refused named among the
/// joints not planned beside them. With none planned, the refusal of the
/// first face (the one holding the most points), as for a lone face.
pub(super) fn plan_faces(
    ctx: &mut Context,
    faces: &[StandingFace],
    flange: &[PlaneCluster],
) -> Result<Welds, PlanError> {
    plan_faces_with(ctx, faces, flange, |face| face_evidence(face, flange))
}

/// [`plan_faces`], each face's tee told what was seen by `evidence`.
fn plan_faces_with(
    ctx: &mut Context,
    faces: &[StandingFace],
    flange: &[PlaneCluster],
    evidence: impl Fn(&StandingFace) -> String,
) -> Result<Welds, PlanError> {
    let mut planned = Vec::new();
    let mut unplanned = Vec::new();
    let mut refused: Vec<(Vec3, PlanError)> = Vec::new();
    for face in faces {
        let layers = evidence(face);
        match tee::plan(ctx, face_tee(face, flange.iter().collect()), layers) {
            Ok((welds, named)) => {
                planned.extend(welds);
                unplanned.extend(named);
            }
            Err(reason) if reason.out_of_time => return Err(reason),
            Err(reason) => refused.push((face.centroid, reason)),
        }
    }
    if planned.is_empty() {
        let (_, first) = refused.swap_remove(0);
        return Err(first);
    }
    unplanned.extend(refused.into_iter().map(|(near, reason)| Unplanned {
        joint: Some(JointType::TFillet),
        near_camera: Some(near),
        reason,
    }));
    Ok((planned, unplanned))
}

/// Both readings refused: the refusal of the one that got further (the
/// later stage; the layers' at the same stage), which says most about the
/// cloud. The face's (or any tee reading's) is named a tee and says, after
/// `read_as` (what the layers read: "read as a lap"), why the layers'
/// reading failed; a plan out of time says only that.
pub(super) fn further(layers: Refused, face: PlanError, read_as: &str) -> Refused {
    if face.out_of_time {
        return Refused { reason: face, seen: Some(JointType::TFillet) };
    }
    if face.stage <= layers.reason.stage {
        return layers;
    }
    let reason = format!("{}; {read_as}: {}", face.reason, layers.reason.reason);
    Refused { reason: PlanError { reason, ..face }, seen: Some(JointType::TFillet) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::Stage;

    fn layers_refused() -> Refused {
        let reason = PlanError::by(&rules::weld_edges::NO_PARALLEL_PAIR, "no parallel pair");
        Refused { reason, seen: None }
    }

    #[test]
    fn a_root_refused_at_its_gates_says_more_than_edges_never_found() {
        let face = PlanError::by(&rules::quality::EDGE_FIT_RESIDUAL, "the root bends by 3.5 mm over 21 mm");
        let picked = further(layers_refused(), face, "read as a butt pair");
        assert_eq!(picked.reason.rule.id, "seam.edge_fit_residual");
        assert_eq!(picked.seen, Some(JointType::TFillet));
        assert!(picked.reason.reason.contains("read as a butt pair: no parallel pair"), "{}", picked.reason);
    }

    #[test]
    fn a_face_refused_no_further_than_the_layers_leaves_the_layers_refusal() {
        // Where the face is refused before its root's gates (here a
        // background rule), the layers' reading stands, as without it.
        let face = PlanError::by(&rules::background::NO_LAYOUT_FITS, "earlier");
        assert_eq!(further(layers_refused(), face, "read as a lap").reason.rule.id, "edge.no_parallel_pair");
        let same = PlanError::by_in(&rules::weld_edges::NO_PARALLEL_PAIR, Stage::WeldEdges, "same stage");
        let picked = further(layers_refused(), same, "read as a lap");
        assert_eq!((picked.reason.reason.as_str(), picked.seen), ("no parallel pair", None));
    }

    #[test]
    fn a_plan_out_of_time_is_named_so() {
        let mut face = PlanError::by(&rules::refit::TEE_NO_ROOT_SEEN, "stopped");
        face.out_of_time = true;
        assert!(further(layers_refused(), face, "read as a butt pair").reason.out_of_time);
    }
}
