//! A daemon in this process on loopback ports the system chooses: the
//! whole cell for `weldseam demo`, the daemon `weldseam bench` measures,
//! and the daemon the integration tests talk to. It is [`super::run`] with
//! listeners (every link's) bound to 127.0.0.1 port 0 and a stop signal, so every caller
//! starts and stops it the same way.

use std::net::{Ipv4Addr, SocketAddr};
use std::sync::Arc;

use tokio::net::TcpListener;
use tokio::sync::oneshot;
use tokio::task::JoinHandle;

use super::jobs::PoolError;
use super::{ServerError, ServerState, Stopped};
use crate::config::Config;

/// Why a local daemon could not start.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    #[error("cannot bind a loopback port for the {link}: {source}")]
    Bind {
        link: &'static str,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot start the pipeline pool: {0}")]
    Pool(#[from] PoolError),
}

/// Why a local daemon did not stop cleanly.
#[derive(Debug, thiserror::Error)]
pub enum StopError {
    #[error(transparent)]
    Server(#[from] ServerError),
    /// The daemon's task panicked or was cancelled.
    #[error("the daemon's task ended abnormally: {0}")]
    Task(#[from] tokio::task::JoinError),
}

/// A running in-process daemon. Dropping it stops the daemon too (its stop
/// signal closes) without waiting; [`LocalDaemon::stop`] waits.
#[derive(Debug)]
pub struct LocalDaemon {
    /// Where cameras connect.
    pub camera_addr: SocketAddr,
    /// Where controllers connect.
    pub controller_addr: SocketAddr,
    /// Where robot programs connect to the text link.
    pub text_addr: SocketAddr,
    /// The HTTP listener (the metrics and the operator page), when started
    /// with [`LocalDaemon::start_with_metrics`].
    pub metrics_addr: Option<SocketAddr>,
    /// The state the daemon's handlers share: its config, frames and counters.
    pub state: Arc<ServerState>,
    stop: Option<oneshot::Sender<()>>,
    server: JoinHandle<Result<Stopped, ServerError>>,
    metrics: Option<JoinHandle<()>>,
}

async fn bind_loopback(link: &'static str) -> Result<(TcpListener, SocketAddr), StartError> {
    let bind = |source| StartError::Bind { link, source };
    let listener = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).await.map_err(bind)?;
    let addr = listener.local_addr().map_err(bind)?;
    Ok((listener, addr))
}

impl LocalDaemon {
    /// Starts a daemon with `config` (its listen addresses are ignored) on
    /// two fresh loopback ports. Call it inside a tokio runtime.
    pub async fn start(config: Config) -> Result<Self, StartError> {
        Self::start_inner(config, None, false).await
    }

    /// As [`LocalDaemon::start`] for `config` read from `config_text`,
    /// which plan records keep, as `serve --config` does.
    pub async fn start_with_config_text(config: Config, config_text: String) -> Result<Self, StartError> {
        Self::start_inner(config, Some(config_text), false).await
    }

    /// As [`LocalDaemon::start`], with the HTTP listener (the metrics and
    /// the operator page) on a fourth port.
    pub async fn start_with_metrics(config: Config) -> Result<Self, StartError> {
        Self::start_inner(config, None, true).await
    }

    async fn start_inner(config: Config, config_text: Option<String>, with_metrics: bool) -> Result<Self, StartError> {
        let (camera, camera_addr) = bind_loopback("camera link").await?;
        let (controller, controller_addr) = bind_loopback("controller link").await?;
        let (text, text_addr) = bind_loopback("text link").await?;
        let metrics_listener = match with_metrics {
            true => Some(bind_loopback("HTTP listener").await?),
            false => None,
        };
        let state = ServerState::with_config_text(config, config_text)?;
        let metrics_addr = metrics_listener.as_ref().map(|(_, addr)| *addr);
        let metrics =
            metrics_listener.map(|(listener, _)| tokio::spawn(super::http::serve(listener, Arc::clone(&state))));
        let (stop, stopped) = oneshot::channel::<()>();
        let listeners = super::Listeners { camera, controller, text: Some(text) };
        let server = tokio::spawn(super::run(listeners, stopped, Arc::clone(&state)));
        Ok(LocalDaemon {
            camera_addr,
            controller_addr,
            text_addr,
            metrics_addr,
            state,
            stop: Some(stop),
            server,
            metrics,
        })
    }

    /// Asks the daemon to stop and waits for it: plans in flight finish
    /// within the configured grace.
    pub async fn stop(mut self) -> Result<Stopped, StopError> {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        let stopped = (&mut self.server).await?;
        if let Some(metrics) = self.metrics.take() {
            metrics.abort();
        }
        Ok(stopped?)
    }
}

impl Drop for LocalDaemon {
    fn drop(&mut self) {
        if let Some(metrics) = &self.metrics {
            metrics.abort();
        }
    }
}
