//! Helpers shared by the integration-test suites.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use tempfile::TempDir;
use tokio::sync::oneshot;
use tokio::task::JoinHandle;
use weldseam::cloud::PointCloud;
use weldseam::config::Config;
use weldseam::mock::camera::{CameraOptions, MockCamera};
use weldseam::server::Stopped;
use weldseam::server::local::LocalDaemon;

/// Writes `bytes` to a file named `name` in a fresh temporary directory.
/// The file lives as long as the returned directory guard.
pub fn write_temp(name: &str, bytes: &[u8]) -> (TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("create a temporary directory");
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).expect("write the temporary file");
    (dir, path)
}

/// A daemon on loopback port 0 and its two addresses as the peers dial
/// them, for the suites that drive it over sockets; each suite adds its
/// own ways in.
pub struct Cell {
    pub camera: String,
    pub controller: String,
    pub daemon: LocalDaemon,
}

impl Cell {
    pub async fn start(config: Config) -> Cell {
        let daemon = LocalDaemon::start(config).await.unwrap();
        Cell { camera: daemon.camera_addr.to_string(), controller: daemon.controller_addr.to_string(), daemon }
    }

    /// Starts a mock camera serving `frames` to the cell; it stops with the
    /// returned sender.
    pub fn camera(
        &self,
        frames: Vec<Arc<PointCloud>>,
        options: CameraOptions,
    ) -> (oneshot::Sender<()>, JoinHandle<()>) {
        let (tx, rx) = oneshot::channel::<()>();
        let cam = MockCamera::new(self.camera.clone(), frames, options);
        let handle = tokio::spawn(async move {
            let _ = cam.run(rx).await;
        });
        (tx, handle)
    }

    /// Stops the daemon; a stop that takes a minute is a hang.
    pub async fn shutdown(self) -> Stopped {
        tokio::time::timeout(Duration::from_secs(60), self.daemon.stop()).await.unwrap().unwrap()
    }
}
