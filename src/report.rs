//! Conversion of planning results into the protocol's report types, the
//! one place where library types meet serializable ones.

use std::collections::BTreeMap;

use weldseam_proto::plan as proto;

use crate::geometry::pose::EulerConvention;
use crate::joint::JointType;
use crate::pipeline::{Plan, Seam};

pub fn joint_to_proto(j: JointType) -> proto::Joint {
    match j {
        JointType::VButt => proto::Joint::VButt,
        JointType::IButt => proto::Joint::IButt,
        JointType::Lap => proto::Joint::Lap,
    }
}

pub fn joint_from_proto(j: proto::Joint) -> JointType {
    match j {
        proto::Joint::VButt => JointType::VButt,
        proto::Joint::IButt => JointType::IButt,
        proto::Joint::Lap => JointType::Lap,
    }
}

fn arr(v: &nalgebra::Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn seam(s: &Seam, euler: EulerConvention) -> proto::Seam {
    proto::Seam {
        joint: joint_to_proto(s.joint),
        waypoints: s
            .waypoints
            .iter()
            .map(|w| proto::Waypoint { xyz: arr(&w.position), rpy_deg: euler.angles(&w.orientation) })
            .collect(),
        start_camera: arr(&s.start_camera),
        end_camera: arr(&s.end_camera),
        normal_camera: arr(&s.normal_camera),
        length_mm: s.length_mm,
        edge_fit_rms_mm: s.edge_fit_rms_mm,
        edge_samples: s.edge_samples.map(|n| n as u32),
        edge_samples_dropped: s.edge_samples_dropped.map(|n| n as u32),
    }
}

/// The report of `plan`, with orientations in `euler`'s angles.
pub fn plan_result(plan: &Plan, euler: EulerConvention) -> proto::PlanResult {
    let mut timing_ms: BTreeMap<String, f64> =
        plan.timings.stages.iter().map(|(stage, ms)| (stage.name().to_string(), *ms)).collect();
    timing_ms.insert("total".into(), plan.timings.total_ms());
    let s = &plan.stats;
    proto::PlanResult {
        seams: plan.seams.iter().map(|x| seam(x, euler)).collect(),
        timing_ms,
        method: plan.method.name().into(),
        euler_convention: euler.name().into(),
        points: proto::PointCounts {
            valid: s.valid_points as u64,
            plane: s.plane_points as u64,
            clusters: s.clusters as u32,
            plates: s.plate_points.map(|n| n as u64),
            edges: s.edge_points.map(|n| n as u64),
            edge_lines: s.edge_lines as u32,
        },
    }
}
