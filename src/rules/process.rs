//! The rules of the weld process along a seam, applied in the trajectory
//! stage once the seam's waypoints are sampled and a procedure is
//! configured (`process.procedure`): stretches of a seam the procedure
//! cannot weld are cut from it, each reported with the figure and the
//! limit or the point of contact. They are listed in the trajectory
//! stage's catalogue (`trajectory.rs`), whose stage applies them.

#[allow(unused_imports)]
use super::{Effect, Gate, Parameter, Rule, Source, Stage};

const PROCEDURE: Parameter = Parameter {
    name: "procedure",
    unit: "file",
    meaning: "the weld procedure (WPS) the waypoints' parameters follow",
    source: Source::Config("process.procedure"),
};

pub static FIGURES_UNMEASURED: Rule = Rule {
    id: "process.figures_unmeasured",
    stage: Stage::Trajectory,
    effect: Effect::CutsSeam,
    gate: None,
    summary: "a stretch whose joint figures are not measured is cut from the welded seam",
    reason: "The arc's settings follow the joint at each waypoint: its gap, its groove, its step, and the plates' \
             thickness that picks the procedure's entry. Where the points near a waypoint do not give the figures \
             (an edge unseen there, a groove whose root no bevel shows) or the thickness is neither configured nor \
             shown by the joint, any setting would be a guess; the stretch is left unwelded and named, the rest \
             of the seam keeps its parameters.",
    parameters: &[
        PROCEDURE,
        Parameter {
            name: "plate_thickness_mm",
            unit: "mm",
            meaning: "the plates' thickness; 0 takes it from the joint where the cloud shows it",
            source: Source::Config("process.plate_thickness_mm"),
        },
        Parameter {
            name: "MIN_SLAB_SAMPLES",
            unit: "samples",
            meaning: "the fewest samples of each weld edge near a waypoint its figures are read from",
            source: Source::Constant { file: "src/pipeline/along_seam.rs", name: "MIN_SLAB_SAMPLES" },
        },
    ],
    fires: &["src/pipeline/seam_process.rs::stretches_the_procedure_cannot_weld_are_cut_and_named"],
    holds: &["src/pipeline/seam_process.rs::a_gap_that_opens_along_the_seam_sets_the_arc_at_every_waypoint"],
};

pub static OUTSIDE_PROCEDURE: Rule = Rule {
    id: "process.outside_procedure",
    stage: Stage::Trajectory,
    effect: Effect::CutsSeam,
    gate: None,
    summary: "a stretch whose measured joint lies outside the procedure's ranges is cut from the welded seam",
    reason: "A procedure is qualified for the joints it lists: per joint type and plate thickness, the widest root \
             gap it welds (AWS D1.1 allows a fillet no gap over 4.8 mm) and the largest bead one pass lays at its \
             slowest travel and fastest wire feed. Where the measured joint breaks one, welding it anyway would \
             lay an unqualified weld; the stretch is cut with the figure and the limit, not the whole seam.",
    parameters: &[PROCEDURE],
    fires: &["src/pipeline/seam_process.rs::stretches_the_procedure_cannot_weld_are_cut_and_named"],
    holds: &["src/pipeline/seam_process.rs::a_gap_that_opens_along_the_seam_sets_the_arc_at_every_waypoint"],
};

pub static TORCH_BLOCKED: Rule = Rule {
    id: "process.torch_blocked",
    stage: Stage::Trajectory,
    effect: Effect::CutsSeam,
    gate: None,
    summary: "a stretch where the torch touches the measured cloud at every angle the procedure allows is cut",
    reason: "The torch is a solid (nozzle and body, grown by a margin) placed at each waypoint at the procedure's \
             angles and checked against the frame's points. Where it touches (a clamp, a high plate, a tee's web) \
             the angles are moved within the procedure's limits, nearest first; where none clears, welding the \
             stretch would drive the torch into the workpiece, so it is cut and reported with the point of \
             contact.",
    parameters: &[
        PROCEDURE,
        Parameter {
            name: "ANGLE_SEARCH_STEP_DEG",
            unit: "degrees",
            meaning: "the step of the search for torch angles that clear",
            source: Source::Constant { file: "src/process/clearance.rs", name: "ANGLE_SEARCH_STEP_DEG" },
        },
    ],
    fires: &["src/pipeline/seam_process.rs::stretches_the_procedure_cannot_weld_are_cut_and_named"],
    holds: &["src/pipeline/seam_process.rs::a_gap_that_opens_along_the_seam_sets_the_arc_at_every_waypoint"],
};
