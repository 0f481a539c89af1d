//! The daemon's HTTP listener (`server.metrics_listen`, off by default):
//! the Prometheus metrics at `/metrics` and the operator page at `/`, with
//! the JSON it reads ([`super::board`]):
//!
//! - `GET /`, `/page.css`, `/page.js`: the page, compiled into the binary;
//! - `GET /api/state`: links, peers, the last frame, the queue, the last
//!   plans and the record store, which the page polls;
//! - `GET /api/plans/SEQ`: one plan's summary, waypoints and figures, and
//!   per seam its figures along it and its weld process in brief
//!   ([`super::board::ProcessSummary`]);
//! - `GET /api/plans/SEQ/camera.png`, `.../sections.png`, `.../profile.png`:
//!   its pictures.
//!
//! It is outside input like the links, so it is bounded the same way: a
//! few connections at once (more are closed at accept), one request per
//! connection, every connection closed after a fixed time whether or not
//! its client reads, and only these routes answered, with GET. Nothing
//! served changes the cell. When `server.http_token` is set, every request
//! for the cell's data (all but the page's own three files) must carry it
//! (`Authorization: Bearer TOKEN` or `?token=TOKEN`; the page opened as
//! `/?token=TOKEN` passes it on); the config refuses a listener beyond
//! loopback without one, and such a listener with none configured answers
//! every request for data with 401.

use std::convert::Infallible;
use std::sync::Arc;
use std::time::Duration;

use bytes::Bytes;
use http_body_util::Full;
use hyper::body::Incoming;
use hyper::{Method, Request, Response, StatusCode};
use hyper_util::rt::{TokioIo, TokioTimer};
use serde_json::json;
use tokio::net::TcpListener;
use tokio::sync::Semaphore;
use tracing::{Instrument, debug, info, warn};

use super::ServerState;
use super::board::ProcessSummary;
use super::frames::wall_clock_us;

/// Connections served at once; a further one is closed at accept. The
/// page asks for one thing at a time, a scraper likewise.
const MAX_CONNECTIONS: usize = 8;

/// The longest a connection may stay open, request and answer: a client
/// that never reads is closed then.
const CONNECTION_TIMEOUT: Duration = Duration::from_secs(10);

const PAGE_HTML: &str = include_str!("page/index.html");
const PAGE_CSS: &str = include_str!("page/page.css");
const PAGE_JS: &str = include_str!("page/page.js");

/// Serves the metrics and the page on `listener` until the future is dropped.
pub async fn serve(listener: TcpListener, state: Arc<ServerState>) {
    let loopback = listener.local_addr().is_ok_and(|a| a.ip().is_loopback());
    if let Ok(addr) = listener.local_addr() {
        info!(%addr, "serving the operator page at / and the metrics at /metrics");
    }
    let token: Access = match (&state.config.server.http_token, loopback) {
        (Some(token), _) => Access::Token(Arc::from(token.as_str())),
        (None, true) => Access::Open,
        (None, false) => {
            warn!("the HTTP listener is not on loopback and server.http_token is empty: every request is refused");
            Access::Closed
        }
    };
    state.board.show_pictures();
    let slots = Arc::new(Semaphore::new(MAX_CONNECTIONS));
    loop {
        let (stream, peer) = match listener.accept().await {
            Ok(accepted) => accepted,
            Err(e) => {
                warn!("http: accept failed: {e}");
                tokio::time::sleep(Duration::from_millis(100)).await;
                continue;
            }
        };
        let Ok(permit) = Arc::clone(&slots).try_acquire_owned() else {
            debug!(%peer, "http: {MAX_CONNECTIONS} connections in progress; closed");
            continue;
        };
        let (state, token) = (Arc::clone(&state), token.clone());
        let span = tracing::debug_span!("http", %peer);
        tokio::spawn(
            async move {
                let service = hyper::service::service_fn(move |request: Request<Incoming>| {
                    let response = respond(&request, &state, &token);
                    async move { Ok::<_, Infallible>(response) }
                });
                let connection = hyper::server::conn::http1::Builder::new()
                    .keep_alive(false)
                    .timer(TokioTimer::new())
                    .header_read_timeout(CONNECTION_TIMEOUT)
                    .serve_connection(TokioIo::new(stream), service);
                match tokio::time::timeout(CONNECTION_TIMEOUT, connection).await {
                    Ok(Ok(())) => {}
                    Ok(Err(e)) => debug!("http: {e}"),
                    Err(_) => debug!("http: closed after {} s", CONNECTION_TIMEOUT.as_secs()),
                }
                drop(permit);
            }
            .instrument(span),
        );
    }
}

/// Who may read.
#[derive(Debug, Clone)]
enum Access {
    /// Anyone who can reach a loopback listener.
    Open,
    /// A request carrying the token.
    Token(Arc<str>),
    /// Nobody: a listener beyond loopback without a token.
    Closed,
}

impl Access {
    fn admits<B>(&self, request: &Request<B>) -> bool {
        match self {
            Access::Open => true,
            Access::Closed => false,
            Access::Token(token) => {
                presented_token(request).is_some_and(|given| same(given.as_bytes(), token.as_bytes()))
            }
        }
    }
}

/// The token a request carries: its bearer authorization, or its `token`
/// query parameter.
fn presented_token<B>(request: &Request<B>) -> Option<String> {
    let bearer = request
        .headers()
        .get(hyper::header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
        .map(|t| t.trim().to_string());
    bearer.or_else(|| query_param(request.uri().query()?, "token"))
}

/// The value of `name` in a query string, percent-decoded.
fn query_param(query: &str, name: &str) -> Option<String> {
    let raw = query.split('&').find_map(|pair| pair.strip_prefix(name)?.strip_prefix('='))?;
    percent_decode(raw)
}

fn percent_decode(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut k = 0;
    while k < bytes.len() {
        match bytes[k] {
            b'%' => {
                let hex = std::str::from_utf8(bytes.get(k + 1..k + 3)?).ok()?;
                out.push(u8::from_str_radix(hex, 16).ok()?);
                k += 3;
            }
            b'+' => {
                out.push(b' ');
                k += 1;
            }
            b => {
                out.push(b);
                k += 1;
            }
        }
    }
    String::from_utf8(out).ok()
}

/// Compares in time independent of where the first difference lies, so
/// the answer's timing does not tell a guesser how much it got right.
fn same(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

type Answer = (StatusCode, &'static str, Bytes);

fn text(status: StatusCode, body: &'static str) -> Answer {
    (status, "text/plain; charset=utf-8", Bytes::from_static(body.as_bytes()))
}

fn respond<B>(request: &Request<B>, state: &ServerState, access: &Access) -> Response<Full<Bytes>> {
    let path = request.uri().path();
    // The page's own files hold no data of the cell; the page reads the
    // data with the token it was opened with.
    let public = matches!(path, "/" | "/page.css" | "/page.js");
    let (status, content_type, body) = if !public && !access.admits(request) {
        text(
            StatusCode::UNAUTHORIZED,
            "this listener needs server.http_token: send it as Authorization: Bearer TOKEN or ?token=TOKEN\n",
        )
    } else if request.method() != Method::GET {
        text(StatusCode::METHOD_NOT_ALLOWED, "only GET is served: nothing here changes the cell\n")
    } else {
        route(path, state)
    };
    let mut response = Response::new(Full::new(body));
    *response.status_mut() = status;
    let headers = response.headers_mut();
    for (name, value) in [
        (hyper::header::CONTENT_TYPE, content_type),
        (hyper::header::CACHE_CONTROL, "no-store"),
        (hyper::header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
        (hyper::header::REFERRER_POLICY, "no-referrer"),
        // Only the page's own files, nothing from elsewhere, no inline script.
        (hyper::header::CONTENT_SECURITY_POLICY, "default-src 'self'; frame-ancestors 'none'"),
    ] {
        if let Ok(value) = value.parse() {
            headers.insert(name, value);
        }
    }
    if status == StatusCode::UNAUTHORIZED
        && let Ok(value) = "Bearer".parse()
    {
        headers.insert(hyper::header::WWW_AUTHENTICATE, value);
    }
    response
}

fn route(path: &str, state: &ServerState) -> Answer {
    let json = |value: serde_json::Value| {
        (StatusCode::OK, "application/json", Bytes::from(serde_json::to_vec(&value).unwrap_or_default()))
    };
    match path {
        "/" => (StatusCode::OK, "text/html; charset=utf-8", Bytes::from_static(PAGE_HTML.as_bytes())),
        "/page.css" => (StatusCode::OK, "text/css; charset=utf-8", Bytes::from_static(PAGE_CSS.as_bytes())),
        "/page.js" => (StatusCode::OK, "text/javascript; charset=utf-8", Bytes::from_static(PAGE_JS.as_bytes())),
        "/metrics" => {
            (StatusCode::OK, super::metrics::CONTENT_TYPE, Bytes::from(state.metrics.encode(state.jobs.len())))
        }
        "/api/state" => json(state_json(state)),
        _ => match path.strip_prefix("/api/plans/").map(plan_route) {
            Some(Some((seq, part))) => plan_answer(state, seq, part),
            _ => text(StatusCode::NOT_FOUND, "not served here: the page is at /, the metrics at /metrics\n"),
        },
    }
}

/// What of a plan a path asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PlanPart {
    Figures,
    CameraView,
    Sections,
    Profile,
}

/// `SEQ`, `SEQ/camera.png`, `SEQ/sections.png` or `SEQ/profile.png`.
fn plan_route(rest: &str) -> Option<(u64, PlanPart)> {
    let (seq, part) = match rest.split_once('/') {
        None => (rest, PlanPart::Figures),
        Some((seq, "camera.png")) => (seq, PlanPart::CameraView),
        Some((seq, "sections.png")) => (seq, PlanPart::Sections),
        Some((seq, "profile.png")) => (seq, PlanPart::Profile),
        Some(_) => return None,
    };
    Some((seq.parse().ok()?, part))
}

fn plan_answer(state: &ServerState, seq: u64, part: PlanPart) -> Answer {
    let gone = || text(StatusCode::NOT_FOUND, "that plan is no longer on the page (server.page_plans)\n");
    let Some(entry) = state.board.plan(seq) else { return gone() };
    let png = |bytes: Option<&Vec<u8>>| match bytes {
        Some(bytes) => (StatusCode::OK, "image/png", Bytes::from(bytes.clone())),
        None => text(StatusCode::NOT_FOUND, "this plan has no such picture\n"),
    };
    match part {
        PlanPart::CameraView => png(entry.pictures.as_ref().map(|p| &p.camera_png)),
        PlanPart::Sections => png(entry.pictures.as_ref().and_then(|p| p.sections_png.as_ref())),
        PlanPart::Profile => png(entry.pictures.as_ref().and_then(|p| p.profile_png.as_ref())),
        PlanPart::Figures => {
            let figures: Option<serde_json::Value> =
                entry.pictures.as_ref().and_then(|p| serde_json::from_slice(&p.figures_json).ok());
            // The seam's JSON form leaves out its figures along it and its
            // process; the page has them beside each seam.
            let seams: Vec<serde_json::Value> = entry
                .result
                .iter()
                .flat_map(|r| &r.seams)
                .map(|s| json!({ "along_seam": s.along_seam, "process": ProcessSummary::of(s.process.as_ref()) }))
                .collect();
            let body = json!({ "plan": entry.summary, "result": entry.result, "seams": seams, "figures": figures });
            (StatusCode::OK, "application/json", Bytes::from(serde_json::to_vec(&body).unwrap_or_default()))
        }
    }
}

/// What `/api/state` answers.
fn state_json(state: &ServerState) -> serde_json::Value {
    let (plans, peers, last_frame) = state.board.snapshot();
    let status = state.status();
    let s = &state.config.server;
    let links: Vec<serde_json::Value> = ["camera", "controller", "text"]
        .into_iter()
        .map(|link| json!({ "link": link, "connections": peers.iter().filter(|p| p.link == link).count() }))
        .collect();
    json!({
        "now_us": wall_clock_us(),
        "server": super::camera_link::server_name(),
        "uptime_ms": status.uptime_ms,
        "frames_received": status.frames_received,
        "plans_done": status.plans_done,
        "links": links,
        "peers": peers,
        "last_frame": last_frame,
        "queue": {
            "jobs": state.jobs.len(),
            "depth": s.plan_queue_depth,
            "frames_awaited": state.frames.waiting(),
        },
        "plans": plans,
        "records": state.records_state(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(uri: &str, authorization: Option<&str>) -> Request<()> {
        let mut builder = Request::builder().uri(uri);
        if let Some(a) = authorization {
            builder = builder.header("authorization", a);
        }
        builder.body(()).unwrap()
    }

    #[test]
    fn a_token_is_taken_from_the_header_or_the_query_and_compared_whole() {
        let access = Access::Token(Arc::from("0123456789abcdef"));
        assert!(access.admits(&request("/api/state", Some("Bearer 0123456789abcdef"))));
        assert!(access.admits(&request("/?x=1&token=0123456789abcdef", None)));
        assert!(access.admits(&request("/?token=0123456789abcde%66", None)));
        assert!(!access.admits(&request("/?token=0123456789abcde", None)));
        assert!(!access.admits(&request("/", Some("Bearer 0123456789abcdeF"))));
        assert!(!access.admits(&request("/", None)));
        assert!(!Access::Closed.admits(&request("/?token=0123456789abcdef", None)));
        assert!(Access::Open.admits(&request("/", None)));
    }

    #[test]
    fn only_a_plan_number_and_its_three_pictures_are_plan_routes() {
        assert_eq!(plan_route("12"), Some((12, PlanPart::Figures)));
        assert_eq!(plan_route("12/camera.png"), Some((12, PlanPart::CameraView)));
        assert_eq!(plan_route("12/sections.png"), Some((12, PlanPart::Sections)));
        assert_eq!(plan_route("12/profile.png"), Some((12, PlanPart::Profile)));
        assert_eq!(plan_route("12/../../etc"), None);
        assert_eq!(plan_route("x/camera.png"), None);
        assert_eq!(percent_decode("%4"), None);
    }
}
