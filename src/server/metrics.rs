//! The daemon's figures for a plant's monitoring: counters, gauges and a
//! histogram that the links update as they go, and an HTTP endpoint that
//! serves them in the OpenMetrics text format, which Prometheus scrapes,
//! when `server.metrics_listen` is set (it is off by default).
//!
//! The HTTP listener that serves them, beside the operator page, is
//! [`super::http`].
//!
//! Refusals and warnings are counted per rule of the planner
//! (`weldseam_refusals_total{rule="..."}`, `weldseam_warnings_total`),
//! each series made when its rule first fires. Their label is a rule's id
//! from [`crate::rules`]'s catalogue, never a value from outside, so the
//! series are at most as many as the catalogue has rules.

use std::time::Duration;

use prometheus_client::encoding::EncodeLabelSet;
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::Registry;
use tracing::warn;
use weldseam_proto::ErrorCode;
use weldseam_proto::message::Role;

use crate::rules::{self, Rule};

/// The content type of the OpenMetrics text format.
pub const CONTENT_TYPE: &str = "application/openmetrics-text; version=1.0.0; charset=utf-8";

#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
struct OutcomeLabels {
    /// "planned", or the name of the error code answered.
    outcome: &'static str,
}

#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
struct LinkLabels {
    link: &'static str,
}

#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RefusedLabels {
    link: &'static str,
    reason: &'static str,
}

#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
struct RuleLabels {
    /// A rule's id, from the catalogue only.
    rule: &'static str,
}

/// Why the acceptor closed a connection it did not serve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// The peer's address is not in the link's allowlist.
    NotAllowed,
    /// No complete Hello within `server.hello_timeout_ms`.
    HelloTimeout,
    /// Closed before its Hello to make room for a newer connection.
    Evicted,
    /// A valid Hello, but every slot of the link was in use.
    LinkFull,
}

impl Refusal {
    pub fn name(self) -> &'static str {
        match self {
            Refusal::NotAllowed => "not_allowed",
            Refusal::HelloTimeout => "hello_timeout",
            Refusal::Evicted => "evicted",
            Refusal::LinkFull => "link_full",
        }
    }
}

/// Every figure the daemon exports.
pub struct Metrics {
    registry: Registry,
    plans: Family<OutcomeLabels, Counter>,
    reply_seconds: Histogram,
    frames: Counter,
    bytes_received: Family<LinkLabels, Counter>,
    queue_depth: Gauge,
    connections: Family<LinkLabels, Gauge>,
    pending: Family<LinkLabels, Gauge>,
    refused: Family<RefusedLabels, Counter>,
    refusals: Family<RuleLabels, Counter>,
    warnings: Family<RuleLabels, Counter>,
    records_written: Counter,
    records_failed: Counter,
    records_dropped: Counter,
    records_held: Gauge,
    records_bytes: Gauge,
}

impl std::fmt::Debug for Metrics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Metrics").finish_non_exhaustive()
    }
}

impl Default for Metrics {
    fn default() -> Self {
        Self::new()
    }
}

/// Decrements its gauge when dropped: a connection counted while it lives.
#[derive(Debug)]
pub struct GaugeGuard(Gauge);

impl Drop for GaugeGuard {
    fn drop(&mut self) {
        self.0.dec();
    }
}

impl Metrics {
    pub fn new() -> Self {
        let m = Metrics {
            registry: Registry::with_prefix("weldseam"),
            plans: Family::default(),
            // 5 ms to about 80 s: a plan, a wait for a fresh frame, a queue.
            reply_seconds: Histogram::new(exponential_buckets(0.005, 2.0, 15)),
            frames: Counter::default(),
            bytes_received: Family::default(),
            queue_depth: Gauge::default(),
            connections: Family::default(),
            pending: Family::default(),
            refused: Family::default(),
            refusals: Family::default(),
            warnings: Family::default(),
            records_written: Counter::default(),
            records_failed: Counter::default(),
            records_dropped: Counter::default(),
            records_held: Gauge::default(),
            records_bytes: Gauge::default(),
        };
        let mut registry = Registry::with_prefix("weldseam");
        registry.register("plans", "Plan requests answered, by outcome (planned or the error code)", m.plans.clone());
        registry.register(
            "reply_seconds",
            "Time from a plan request's arrival to its reply (plan or error), seconds",
            m.reply_seconds.clone(),
        );
        registry.register("frames", "Frames received and stored", m.frames.clone());
        registry.register("received_bytes", "Bytes received, by link", m.bytes_received.clone());
        registry.register("queue_depth", "Plan jobs queued or running", m.queue_depth.clone());
        registry.register("connections", "Connections past their Hello, by link", m.connections.clone());
        registry.register("pending_connections", "Connections yet to say Hello, by link", m.pending.clone());
        registry.register("refused_peers", "Connections closed unserved, by link and reason", m.refused.clone());
        registry.register(
            "refusals",
            "Plans and joints refused, by the planner's rule that refused them (docs/RULES.md)",
            m.refusals.clone(),
        );
        registry.register(
            "warnings",
            "Seams planned with a warning, by the planner's rule that warned (docs/RULES.md)",
            m.warnings.clone(),
        );
        registry.register("records_written", "Plan records written ([records])", m.records_written.clone());
        registry.register(
            "records_failed",
            "Plan records that could not be written (a full disk, an I/O error); the plans were answered",
            m.records_failed.clone(),
        );
        registry.register(
            "records_dropped",
            "Plans not recorded because the previous records were still being written",
            m.records_dropped.clone(),
        );
        registry.register("records_held", "Plan records in the store", m.records_held.clone());
        registry.register("records_bytes", "Bytes of the plan records in the store", m.records_bytes.clone());
        // Both links show from the start, at zero, so a dashboard has a
        // series before the first connection.
        for role in [Role::Camera, Role::Controller] {
            let link = LinkLabels { link: role.name() };
            drop(m.bytes_received.get_or_create(&link));
            drop(m.connections.get_or_create(&link));
            drop(m.pending.get_or_create(&link));
        }
        Metrics { registry, ..m }
    }

    /// Counts a plan request's answer (a plan or an error reply) and the
    /// time since the request arrived.
    pub fn plan_answered(&self, outcome: Result<(), ErrorCode>, since_request: Duration) {
        let outcome = match outcome {
            Ok(()) => "planned",
            Err(code) => code.name(),
        };
        self.plans.get_or_create(&OutcomeLabels { outcome }).inc();
        self.reply_seconds.observe(since_request.as_secs_f64());
    }

    /// Counts a plan request refused before it was queued (invalid, busy).
    pub fn request_refused(&self, code: ErrorCode) {
        self.plans.get_or_create(&OutcomeLabels { outcome: code.name() }).inc();
    }

    /// Counts a refusal (of a request, a plan or a joint left unplanned)
    /// by `rule`.
    pub fn refused_by(&self, rule: &'static Rule) {
        if let Some(label) = catalogued(rule) {
            self.refusals.get_or_create(&label).inc();
        }
    }

    /// Counts a seam's warning by `rule`.
    pub fn warned_by(&self, rule: &'static Rule) {
        if let Some(label) = catalogued(rule) {
            self.warnings.get_or_create(&label).inc();
        }
    }

    /// Counts a plan not recorded because the writers were busy.
    pub fn record_dropped(&self) {
        self.records_dropped.inc();
    }

    /// The record writer's figures: the written and failed counters, and
    /// a setter of the store's size.
    pub fn record_counters(&self) -> (Counter, Counter, impl Fn(crate::records::Held) + Send + 'static) {
        let (held, bytes) = (self.records_held.clone(), self.records_bytes.clone());
        let set = move |h: crate::records::Held| {
            held.set(h.count.try_into().unwrap_or(i64::MAX));
            bytes.set(h.bytes.try_into().unwrap_or(i64::MAX));
        };
        (self.records_written.clone(), self.records_failed.clone(), set)
    }

    /// Counts a frame stored.
    pub fn frame_received(&self) {
        self.frames.inc();
    }

    /// The counter of bytes received on `role`'s link.
    pub fn bytes_counter(&self, role: Role) -> Counter {
        self.bytes_received.get_or_create_owned(&LinkLabels { link: role.name() })
    }

    /// Counts a connection past its Hello until the guard is dropped.
    pub fn connection_opened(&self, role: Role) -> GaugeGuard {
        self.link_connection_opened(role.name())
    }

    /// Counts a connection of the link named `link` (`text` for the text
    /// controller link) until the guard is dropped.
    pub fn link_connection_opened(&self, link: &'static str) -> GaugeGuard {
        let gauge = self.connections.get_or_create_owned(&LinkLabels { link });
        gauge.inc();
        GaugeGuard(gauge)
    }

    /// Counts a connection yet to say Hello until the guard is dropped.
    pub fn pending_opened(&self, role: Role) -> GaugeGuard {
        let gauge = self.pending.get_or_create_owned(&LinkLabels { link: role.name() });
        gauge.inc();
        GaugeGuard(gauge)
    }

    /// Counts a connection closed unserved.
    pub fn peer_refused(&self, role: Role, why: Refusal) {
        self.refused.get_or_create(&RefusedLabels { link: role.name(), reason: why.name() }).inc();
    }

    /// The exposition: every figure, in the OpenMetrics text format.
    pub fn encode(&self, queue_depth: usize) -> String {
        self.queue_depth.set(queue_depth.try_into().unwrap_or(i64::MAX));
        let mut text = String::new();
        // Writing into a String cannot fail.
        let _ = prometheus_client::encoding::text::encode(&mut text, &self.registry);
        text
    }
}

/// The label of a rule of the catalogue; a rule declared outside it is
/// logged and not counted, so the series stay bounded by the catalogue.
fn catalogued(rule: &'static Rule) -> Option<RuleLabels> {
    match rules::by_id(rule.id) {
        Some(known) => Some(RuleLabels { rule: known.id }),
        None => {
            warn!(rule = rule.id, "a rule outside the catalogue is not counted");
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_exposition_names_every_figure() {
        let m = Metrics::new();
        m.plan_answered(Err(ErrorCode::PlanFailed), Duration::from_millis(40));
        m.request_refused(ErrorCode::Busy);
        m.frame_received();
        m.bytes_counter(Role::Camera).inc_by(100);
        let _open = m.connection_opened(Role::Controller);
        {
            let _gone = m.pending_opened(Role::Controller);
        }
        m.peer_refused(Role::Controller, Refusal::Evicted);
        m.refused_by(&rules::input::NO_VALID_POINT);
        m.refused_by(&rules::input::NO_VALID_POINT);
        m.warned_by(&rules::quality::JOINT_COVERAGE);
        let text = m.encode(3);
        for line in [
            "weldseam_plans_total{outcome=\"plan_failed\"} 1",
            "weldseam_plans_total{outcome=\"busy\"} 1",
            "weldseam_reply_seconds_count 1",
            "weldseam_frames_total 1",
            "weldseam_received_bytes_total{link=\"camera\"} 100",
            "weldseam_queue_depth 3",
            "weldseam_connections{link=\"controller\"} 1",
            "weldseam_pending_connections{link=\"controller\"} 0",
            "weldseam_refused_peers_total{link=\"controller\",reason=\"evicted\"} 1",
            "weldseam_refusals_total{rule=\"frame.no_valid_point\"} 2",
            "weldseam_warnings_total{rule=\"seam.joint_coverage\"} 1",
            "weldseam_records_failed_total 0",
            "weldseam_records_bytes 0",
        ] {
            assert!(text.lines().any(|l| l == line), "no line {line:?} in\n{text}");
        }
    }

    #[test]
    fn a_rule_outside_the_catalogue_makes_no_series() {
        static STRAY: Rule = Rule {
            id: "stray.rule",
            stage: rules::Stage::Quality,
            effect: rules::Effect::Refuses,
            gate: None,
            summary: "",
            reason: "",
            parameters: &[],
            fires: &[],
            holds: &[],
        };
        let m = Metrics::new();
        m.refused_by(&STRAY);
        m.warned_by(&STRAY);
        let text = m.encode(0);
        assert!(!text.contains("stray.rule"), "{text}");
        // A rule's series appears only once it fires.
        assert!(!text.contains("frame.no_valid_point"), "{text}");
    }
}
