//! The rules of the input stage (`Stage::Input`): what a frame must hold
//! before any geometry is read from it.

use super::{Effect, Parameter, Rule, Source, Stage};

/// The stage's rules, in the order they apply.
pub(super) static RULES: &[&Rule] =
    &[&NO_VALID_POINT, &TOO_FEW_POINTS_IN_REGION, &NOT_IN_CAMERA_FRAME, &ONE_POINT_REPEATED, &SMALLER_THAN_A_JOINT];

pub static NO_VALID_POINT: Rule = Rule {
    id: "frame.no_valid_point",
    stage: Stage::Input,
    effect: Effect::Refuses,
    gate: None,
    summary: "the frame holds at least one point the camera can measure",
    reason: "A structured-light camera measures only within its working volume: nearer than its minimum \
             depth the projector and the sensor no longer overlap, farther than its maximum the pattern \
             is too faint, and beyond its field of view no pixel looks. A point outside that volume, or \
             one with a coordinate that is not a number, is a decoding error or a frame in the wrong \
             units or frame, never a surface. A frame with no point left has nothing to plan from; the \
             refusal counts the points on each side of the volume, since a whole frame outside it is \
             most often a cloud in metres or in the robot's base frame.",
    parameters: &[
        Parameter {
            name: "min_depth_mm",
            unit: "mm",
            meaning: "nearest depth the camera measures",
            source: Source::Config("camera.min_depth_mm"),
        },
        Parameter {
            name: "max_depth_mm",
            unit: "mm",
            meaning: "farthest depth the camera measures",
            source: Source::Config("camera.max_depth_mm"),
        },
        Parameter {
            name: "max_off_axis_deg",
            unit: "°",
            meaning: "widest angle off the optical axis a point may lie at",
            source: Source::Config("camera.max_off_axis_deg"),
        },
    ],
    fires: &[
        "tests/pipeline.rs::bad_requests_are_refused_before_any_work",
        "tests/pipeline.rs::points_at_the_optical_centre_are_ignored_not_searched_forever",
    ],
    holds: &["tests/hostile_clouds.rs::one_absurd_point_neither_runs_away_nor_changes_the_plan"],
};

pub static TOO_FEW_POINTS_IN_REGION: Rule = Rule {
    id: "frame.too_few_points_in_region",
    stage: Stage::Input,
    effect: Effect::Refuses,
    gate: None,
    summary: "the region of interest keeps enough of the frame's points to hold two plates",
    reason: "The region of interest is where the workpieces are meant to lie. A box that keeps only a few \
             hundred points is placed beside them (the wrong frame, a pose from another capture, a part not \
             yet loaded), and whatever those points show is not the joint meant.",
    parameters: &[Parameter {
        name: "MIN_ROI_POINTS",
        unit: "",
        meaning: "fewest points the box must keep",
        source: Source::Constant { file: "src/pipeline/roi.rs", name: "MIN_ROI_POINTS" },
    }],
    fires: &[
        "tests/daemon/requests.rs::a_region_of_interest_travels_in_the_request_and_bad_ones_are_refused",
        "tests/roi.rs::the_configured_box_applies_unless_the_request_brings_its_own",
    ],
    holds: &["tests/roi.rs::clutter_outside_the_box_plans_as_the_clean_frame"],
};

pub static NOT_IN_CAMERA_FRAME: Rule = Rule {
    id: "frame.not_in_camera_frame",
    stage: Stage::Input,
    effect: Effect::Refuses,
    gate: None,
    summary: "most of the frame's points lie in front of the camera, within a field of view a camera can have, \
              and they spread no wider than a camera sees",
    reason: "A camera sees only in front of itself and within a cone about its optical axis; no depth camera \
             sees farther than about 60 degrees off it, nor wider than about 120 degrees across its image. A \
             cloud most of whose points lie behind the camera or far outside that cone, or whose points, seen \
             from the camera's origin, spread wider across than any camera sees (a workpiece beside a robot, \
             held in the robot's base frame, is seen from the base over 140 degrees and more), is in another \
             frame (the robot's base) or in other units, and a seam planned from it would be placed by the \
             wrong transform.",
    parameters: &[
        Parameter {
            name: "MAX_PLAUSIBLE_OFF_AXIS_DEG",
            unit: "°",
            meaning: "widest angle off the axis any camera sees",
            source: Source::Constant { file: "src/pipeline/input.rs", name: "MAX_PLAUSIBLE_OFF_AXIS_DEG" },
        },
        Parameter {
            name: "MAX_IMPLAUSIBLE_FRACTION",
            unit: "",
            meaning: "largest share of points behind or beyond any view",
            source: Source::Constant { file: "src/pipeline/input.rs", name: "MAX_IMPLAUSIBLE_FRACTION" },
        },
        Parameter {
            name: "MAX_PLAUSIBLE_FIELD_OF_VIEW_DEG",
            unit: "°",
            meaning: "widest spread across either image axis any camera sees",
            source: Source::Constant { file: "src/pipeline/input.rs", name: "MAX_PLAUSIBLE_FIELD_OF_VIEW_DEG" },
        },
        Parameter {
            name: "EXTENT_TRIMMED_SHARE",
            unit: "",
            meaning: "share of sampled points left out at each side of the spread",
            source: Source::Constant { file: "src/pipeline/input.rs", name: "EXTENT_TRIMMED_SHARE" },
        },
    ],
    fires: &[
        "tests/units_frames.rs::clouds_no_camera_could_see_are_refused_with_the_reason",
        "tests/units_frames.rs::a_cloud_spread_wider_than_any_camera_sees_is_refused_as_no_camera_view",
    ],
    holds: &["tests/units_frames.rs::a_base_frame_cloud_plans_the_seam_of_the_camera_frame_one"],
};

pub static ONE_POINT_REPEATED: Rule = Rule {
    id: "frame.one_point_repeated",
    stage: Stage::Input,
    effect: Effect::Refuses,
    gate: None,
    summary: "most of the frame's points are distinct",
    reason: "A camera measures each pixel along its own ray, so its frames repeat a point hardly ever. A frame \
             most of whose points are one and the same is a stuck sensor's or a corrupt transfer's: it shows \
             no surface, and measuring its density would compare every point with every other.",
    parameters: &[Parameter {
        name: "MIN_DISTINCT_SHARE",
        unit: "",
        meaning: "least share of sampled points that are distinct",
        source: Source::Constant { file: "src/pipeline/input.rs", name: "MIN_DISTINCT_SHARE" },
    }],
    fires: &[
        "tests/serve_order.rs::a_frame_of_one_repeated_point_is_refused_and_the_next_plan_goes_on",
        "tests/pipeline.rs::frames_no_camera_makes_are_refused_by_their_rule",
    ],
    holds: &["tests/hostile_clouds.rs::one_absurd_point_neither_runs_away_nor_changes_the_plan"],
};

pub static SMALLER_THAN_A_JOINT: Rule = Rule {
    id: "frame.smaller_than_a_joint",
    stage: Stage::Input,
    effect: Effect::Refuses,
    gate: None,
    summary: "the frame's points spread wider than a few millimetres",
    reason: "Any joint's two plates span several millimetres each. Points that all lie within a box a few \
             millimetres wide show no surface a seam could be planned on; such a frame is a fault of the \
             sensor or the transfer.",
    parameters: &[Parameter {
        name: "MIN_VIEW_EXTENT_MM",
        unit: "mm",
        meaning: "least extent of the points along their widest axis",
        source: Source::Constant { file: "src/pipeline/input.rs", name: "MIN_VIEW_EXTENT_MM" },
    }],
    fires: &["tests/pipeline.rs::frames_no_camera_makes_are_refused_by_their_rule"],
    holds: &["tests/hostile_clouds.rs::one_absurd_point_neither_runs_away_nor_changes_the_plan"],
};
