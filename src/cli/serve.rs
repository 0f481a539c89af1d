//! `weldseam serve`: the cell daemon. Binds its links (and the metrics
//! endpoint when configured), tells systemd it is ready, serves until
//! SIGINT or SIGTERM, then lets plans in flight finish within the
//! configured grace and exits.

use std::net::SocketAddr;
use std::sync::Arc;

use anyhow::Context;
use tokio::net::TcpListener;
use tracing::{info, warn};
use weldseam::server::{self, ServerState, Stopped};

use super::args::ConfigArgs;

#[derive(Debug, clap::Args)]
pub struct ServeArgs {
    #[command(flatten)]
    pub config: ConfigArgs,
    /// Camera link address, overriding server.camera_listen.
    #[arg(long)]
    pub camera_listen: Option<SocketAddr>,
    /// Controller link address, overriding server.controller_listen.
    #[arg(long)]
    pub controller_listen: Option<SocketAddr>,
    /// Text link address, overriding text_link.listen.
    #[arg(long)]
    pub text_listen: Option<SocketAddr>,
    /// Start even when robot.hand_eye_calibration records a calibration
    /// that failed its gate.
    #[arg(long)]
    pub force: bool,
}

/// Logs the hand-eye loaded and its calibration's record; refuses one the
/// record says failed its gate, unless `force`.
fn check_hand_eye(config: &weldseam::config::Config, origin: &str, force: bool) -> anyhow::Result<()> {
    let rows = weldseam::convert::calibration::rows(&config.hand_eye);
    let record = config.hand_eye_calibration.as_ref();
    let figures = record.map_or_else(|| "no calibration record (robot.hand_eye_calibration)".into(), |r| r.summary());
    info!(config = origin, hand_eye = ?rows, calibration = %figures, "hand-eye loaded");
    match record {
        Some(r) if !r.passed && !force => anyhow::bail!(
            "{origin}: robot.hand_eye comes from a calibration that failed its gate ({}), and --force was not given;              calibrate again, or start with --force to run with it anyway",
            r.failures.join("; ")
        ),
        Some(r) if !r.passed => warn!(
            config = origin,
            "--force: running with a hand-eye whose calibration failed: {}",
            r.failures.join("; ")
        ),
        _ => {}
    }
    Ok(())
}

/// Completes on SIGINT or SIGTERM.
async fn termination() -> anyhow::Result<()> {
    let mut term = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate())
        .context("cannot listen for SIGTERM")?;
    tokio::select! {
        r = tokio::signal::ctrl_c() => { r.context("cannot listen for SIGINT")?; info!("SIGINT received"); }
        _ = term.recv() => info!("SIGTERM received"),
    }
    Ok(())
}

pub fn run(args: &ServeArgs) -> anyhow::Result<()> {
    let mut config = args.config.load()?;
    let origin = args.config.config.as_ref().map_or("the built-in config".to_string(), |p| p.display().to_string());
    check_hand_eye(&config, &origin, args.force)?;
    if let Some(a) = args.camera_listen {
        config.server.camera_listen = a;
    }
    if let Some(a) = args.controller_listen {
        config.server.controller_listen = a;
    }
    if let Some(a) = args.text_listen {
        config.text_link.listen = Some(a);
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .thread_name("net")
        .build()
        .context("cannot start the network runtime")?;
    // Plan records keep the file, so that a replay plans with it.
    let text = match &args.config.config {
        Some(path) => Some(std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?),
        None => None,
    };
    runtime.block_on(serve(config, text))
}

async fn serve(config: weldseam::config::Config, config_text: Option<String>) -> anyhow::Result<()> {
    let s = &config.server;
    let camera = TcpListener::bind(s.camera_listen)
        .await
        .with_context(|| format!("cannot listen on {} (server.camera_listen)", s.camera_listen))?;
    let controller = TcpListener::bind(s.controller_listen)
        .await
        .with_context(|| format!("cannot listen on {} (server.controller_listen)", s.controller_listen))?;
    let text = match config.text_link.listen {
        Some(addr) => {
            Some(TcpListener::bind(addr).await.with_context(|| format!("cannot listen on {addr} (text_link.listen)"))?)
        }
        None => None,
    };
    let metrics = match s.metrics_listen {
        Some(addr) => Some(
            TcpListener::bind(addr)
                .await
                .with_context(|| format!("cannot listen on {addr} (server.metrics_listen)"))?,
        ),
        None => None,
    };
    info!(
        camera = %camera.local_addr()?,
        controller = %controller.local_addr()?,
        text = text.as_ref().and_then(|t| t.local_addr().ok()).map(|a| a.to_string()).unwrap_or_else(|| "off".into()),
        pipeline_threads = s.pipeline_threads,
        plan_queue_depth = s.plan_queue_depth,
        "listening"
    );
    let state = ServerState::with_config_text(config, config_text)?;
    if let Err(e) = sd_notify::notify(&[sd_notify::NotifyState::Ready]) {
        warn!("cannot notify systemd of readiness: {e}");
    }
    let shutdown = async {
        if let Err(e) = termination().await {
            warn!("{e:#}; stopping");
        }
        let _ = sd_notify::notify(&[sd_notify::NotifyState::Stopping]);
    };
    if let Some(addr) = metrics.as_ref().and_then(|l| l.local_addr().ok()) {
        info!(page = %format!("http://{addr}/"), "the operator page");
    }
    // The HTTP listener lives until the links have stopped.
    let metrics = metrics.map(|listener| tokio::spawn(server::http::serve(listener, Arc::clone(&state))));
    let stopped = server::run(server::Listeners { camera, controller, text }, shutdown, state).await;
    if let Some(task) = metrics {
        task.abort();
    }
    match stopped? {
        Stopped::Clean | Stopped::GraceExpired => Ok(()),
    }
}
