//! The background stage's rules for a face standing on the nearest plane
//! (`src/pipeline/web_face.rs`): a tee's web whose top is out of view, or
//! a member standing on a plate, read by its side faces; listed in the
//! stage's order in [`super::background::RULES`].

use super::{Effect, Parameter, Rule, Source, Stage};

pub(super) const WEB_FACE: &str = "src/pipeline/web_face.rs";

const MIN_STANDING_FACE_POINTS: Parameter = Parameter {
    name: "MIN_FACE_POINTS",
    unit: "",
    meaning: "fewest points that make a face",
    source: Source::Constant { file: "src/pipeline/fillet/mod.rs", name: "MIN_FACE_POINTS" },
};

pub static TEE_NOTHING_STANDS_ON_FLANGE: Rule = Rule {
    id: "tee.nothing_stands_on_flange",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "with the web's top out of view, points stand over the flange's footprint, up to a web's height",
    reason: "A cloud cropped round a fillet root keeps the flange and the web's side face up to the crop, but \
             not the web's top, so the face itself must show where the web stands. A face turned edge-on to \
             the camera returns no points, and with the top out of view nothing else shows where its root \
             is: with fewer than a face's worth of points standing over the flange, no tee is planned.",
    parameters: &[
        MIN_STANDING_FACE_POINTS,
        Parameter {
            name: "tee_web_height_max_mm",
            unit: "mm",
            meaning: "tallest web searched for",
            source: Source::Config("pipeline.tee_web_height_max_mm"),
        },
    ],
    fires: &[
        "src/pipeline/web_face_tests.rs::a_flange_with_nothing_standing_on_it_or_a_face_too_low_or_over_it_gives_no_face",
    ],
    holds: &["src/pipeline/web_face_tests.rs::a_face_standing_on_the_flange_is_found_through_a_veil_of_mixed_returns"],
};

pub static TEE_NO_FACE_STANDS_ON_FLANGE: Rule = Rule {
    id: "tee.no_face_stands_on_flange",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "the points over the flange lie on a plane standing near square on it and turned towards the camera",
    reason: "A web's side face is a plane standing on its flange, leaning a few degrees at most, and the camera \
             samples it only where it is turned towards the camera's rays. Points over the flange that lie on \
             no such plane (the flange's own points spanning no plane, a jumble of returns, or planes too \
             flat or turned from the camera) are no web's face, and no root is planned from them. The same holds \
             of the plane refitted to the points near the one drawn: a depth jump beside a web leaves a veil of \
             mixed returns hanging along the camera's rays, and a refit that settles on it is not taken.",
    parameters: &[
        Parameter {
            name: "MAX_FACE_LEAN_DEG",
            unit: "°",
            meaning: "widest lean from square searched for",
            source: Source::Constant { file: WEB_FACE, name: "MAX_FACE_LEAN_DEG" },
        },
        Parameter {
            name: "MIN_FACE_VIEW_DEG",
            unit: "°",
            meaning: "least angle between a face and the camera's ray to it",
            source: Source::Constant { file: "src/pipeline/fillet/face.rs", name: "MIN_FACE_VIEW_DEG" },
        },
    ],
    fires: &[
        "src/pipeline/web_face_tests.rs::mixed_returns_alone_are_no_face",
        "tests/consumer_camera.rs::a_v_groove_strip_requested_as_a_tee_is_refused_not_planned_along_its_root_land",
    ],
    holds: &["src/pipeline/web_face_tests.rs::a_face_standing_on_the_flange_is_found_through_a_veil_of_mixed_returns"],
};

pub static TEE_FACE_FOOT_ABOVE_FLANGE: Rule = Rule {
    id: "tee.face_foot_above_flange",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "the face found over the flange comes down to within a few spacings of the flange's plane",
    reason: "A web stands on its flange: its face is seen down to the flange, or to within a few point \
             spacings of it where the flange's own points are kept out. A face seen no lower than that stands \
             over the flange (a fixture, a part held above it), not on it, and has no root there.",
    parameters: &[Parameter {
        name: "FOOT_REACH_SPACINGS",
        unit: "point spacings",
        meaning: "how far above the flange's plane a face's foot may stop",
        source: Source::Constant { file: WEB_FACE, name: "FOOT_REACH_SPACINGS" },
    }],
    fires: &[
        "src/pipeline/web_face_tests.rs::a_flange_with_nothing_standing_on_it_or_a_face_too_low_or_over_it_gives_no_face",
    ],
    holds: &["src/pipeline/web_face_tests.rs::a_face_standing_on_the_flange_is_found_through_a_veil_of_mixed_returns"],
};

pub static TEE_STANDING_FACE_TOO_SPARSE: Rule = Rule {
    id: "tee.standing_face_too_sparse",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "the face's points fill the rectangle they span at least as densely as a face seen at a grazing \
              angle is sampled",
    reason: "A face turned the least angle the camera sees is still sampled at about a tenth of a point per \
             square spacing; stray returns that happen to lie on one steep plane over a large flange are far \
             sparser. Points strewn thinner than half that grazing density are not a face.",
    parameters: &[Parameter {
        name: "MIN_FACE_FILL",
        unit: "points per square spacing",
        meaning: "fewest points per square point spacing over the face's extent",
        source: Source::Constant { file: WEB_FACE, name: "MIN_FACE_FILL" },
    }],
    fires: &["src/pipeline/web_face_tests.rs::stray_returns_on_one_plane_over_a_wide_flange_are_no_face"],
    holds: &["src/pipeline/web_face_tests.rs::a_face_standing_on_the_flange_is_found_through_a_veil_of_mixed_returns"],
};

pub static TEE_STANDING_FACE_TOO_LOW: Rule = Rule {
    id: "tee.standing_face_too_low",
    stage: Stage::Background,
    effect: Effect::Refuses,
    gate: None,
    summary: "the face on the flange is seen at least ten point spacings tall",
    reason: "A face a few spacings tall is a plate's edge or a ridge of noise, not a web, and its tilt, and so \
             where its root lies, is poorly fixed by so short a lever. A face seen lower than ten spacings is \
             not planned from.",
    parameters: &[Parameter {
        name: "MIN_FACE_HEIGHT_SPACINGS",
        unit: "point spacings",
        meaning: "least height a face must be seen to",
        source: Source::Constant { file: WEB_FACE, name: "MIN_FACE_HEIGHT_SPACINGS" },
    }],
    fires: &[
        "src/pipeline/web_face_tests.rs::a_flange_with_nothing_standing_on_it_or_a_face_too_low_or_over_it_gives_no_face",
    ],
    holds: &["src/pipeline/web_face_tests.rs::a_face_standing_on_the_flange_is_found_through_a_veil_of_mixed_returns"],
};
