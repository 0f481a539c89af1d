//! Point clouds in the camera frame, in millimetres, and the file formats
//! they arrive in.
//!
//! A cloud is either *organized* (one point per camera pixel, row-major,
//! `width x height`) or *unorganized* (a bag of points, `height == 1`).
//! Invalid pixels are stored as NaN whatever the source used (NaN, or
//! `0, 0, 0` as some cameras send), so every later stage has one test for
//! validity. The organized structure is kept whenever the source has it:
//! the neighbour search, clustering and boundary refinement use the pixel
//! grid as their fast, exact path.

pub mod pcd;
pub mod ply;
mod reader;

use std::path::PathBuf;

/// One point, camera frame, millimetres. NaN coordinates mean "no return".
pub type Point = [f32; 3];

/// The marker stored for a pixel that has no valid return.
pub const INVALID_POINT: Point = [f32::NAN, f32::NAN, f32::NAN];

/// A point cloud in the camera frame, millimetres.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCloud {
    points: Vec<Point>,
    width: usize,
    height: usize,
    organized: bool,
}

/// Returns true when `p` is a real return: finite and not the `0, 0, 0`
/// marker some cameras use for "no data" (a real surface is never at the
/// optical centre).
#[inline]
pub fn is_valid_point(p: &Point) -> bool {
    p[0].is_finite() && p[1].is_finite() && p[2].is_finite() && !(p[0] == 0.0 && p[1] == 0.0 && p[2] == 0.0)
}

impl PointCloud {
    /// An organized cloud of `width x height` pixels, row-major. Invalid
    /// markers are normalised to NaN.
    ///
    /// Returns `None` when `points.len() != width * height`.
    pub fn organized(width: usize, height: usize, mut points: Vec<Point>) -> Option<Self> {
        if width.checked_mul(height)? != points.len() {
            return None;
        }
        normalise_invalid(&mut points);
        Some(PointCloud { points, width, height, organized: height > 1 })
    }

    /// An unorganized cloud. Invalid points are dropped, since without a
    /// pixel grid their position carries no information.
    pub fn unorganized(mut points: Vec<Point>) -> Self {
        points.retain(is_valid_point);
        let width = points.len();
        PointCloud { points, width, height: 1, organized: false }
    }

    /// All points, row-major for organized clouds. Invalid ones are NaN.
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// The points, taken out of the cloud: for a caller that changes them
    /// and makes a cloud of them again ([`PointCloud::organized`] and
    /// [`PointCloud::unorganized`] keep the vector they are given), so a
    /// frame is changed without a second copy of it.
    pub fn into_points(self) -> Vec<Point> {
        self.points
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    /// True when the points form a pixel grid (`height > 1`).
    pub fn is_organized(&self) -> bool {
        self.organized
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Number of points with a valid return.
    pub fn valid_count(&self) -> usize {
        self.points.iter().filter(|p| p[0].is_finite()).count()
    }

    /// The point at pixel `(col, row)` of an organized cloud, if valid.
    #[inline]
    pub fn at(&self, col: usize, row: usize) -> Option<&Point> {
        let p = &self.points[row * self.width + col];
        p[0].is_finite().then_some(p)
    }
}

fn normalise_invalid(points: &mut [Point]) {
    for p in points.iter_mut() {
        if !is_valid_point(p) {
            *p = INVALID_POINT;
        }
    }
}

/// Why a point-cloud file could not be read. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The path names a device, pipe, socket or directory: only regular
    /// files have a size that bounds what is read.
    #[error("{path} is {kind}, not a regular file")]
    NotAFile { path: PathBuf, kind: &'static str },
    /// The file's extension is neither `.pcd` nor `.ply`.
    #[error("{path}: unknown point cloud format (expected a .pcd or .ply file)")]
    UnknownFormat { path: PathBuf },
    /// The header is malformed: `line` is 1-based.
    #[error("{path}: header line {line}: {message}")]
    Header { path: PathBuf, line: usize, message: String },
    /// The data section is malformed or shorter than the header promises.
    #[error("{path}: data at {location}: {message}")]
    Data { path: PathBuf, location: String, message: String },
}

/// Files from this size on are mapped rather than read: copying a 27.6 MB
/// frame into a fresh buffer cost a one-shot process 18 ms of page faults
/// and copying, half of its load time.
const MAP_FROM_BYTES: u64 = 1 << 20;

/// Reads a PCD or PLY file, choosing the parser by extension.
///
/// Only regular files are read (symlinks to them are followed): a device,
/// pipe or directory has no size to bound the read by, and `/dev/zero`
/// would be read until memory ran out. What is read is bounded by the
/// size the file had when opened, so a file growing meanwhile is cut
/// there; the parser then reads no further than its header promises.
pub fn load(path: &std::path::Path) -> Result<PointCloud, LoadError> {
    use std::io::Read;
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let io = |source| LoadError::Io { path: path.to_path_buf(), source };
    let parse = |bytes: &[u8]| match ext.as_deref() {
        Some("pcd") => pcd::parse(bytes, path),
        Some("ply") => ply::parse(bytes, path),
        _ => Err(LoadError::UnknownFormat { path: path.to_path_buf() }),
    };
    let not_a_file = |metadata: &std::fs::Metadata| LoadError::NotAFile {
        path: path.to_path_buf(),
        kind: file_kind(&metadata.file_type()),
    };
    // Looked at before opening too: opening a pipe blocks until something
    // writes to it, so a pipe given as a cloud would hang the caller.
    let before = std::fs::metadata(path).map_err(io)?;
    if !before.is_file() {
        return Err(not_a_file(&before));
    }
    let file = std::fs::File::open(path).map_err(io)?;
    let metadata = file.metadata().map_err(io)?;
    if !metadata.is_file() {
        return Err(not_a_file(&metadata));
    }
    let len = metadata.len();
    if len >= MAP_FROM_BYTES {
        // SAFETY: the map is only read, and only while parsing. Were another
        // process to rewrite the file meanwhile, the parser would see other
        // bytes, which it checks like any; were it to truncate the file, the
        // read past the new end would fault, as with any mapped file. A
        // frame being written is not a file to plan from either way.
        let map = unsafe { memmap2::MmapOptions::new().map(&file) }.map_err(io)?;
        return parse(&map);
    }
    // Below MAP_FROM_BYTES, so the capacity is small whatever the file says.
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(len).read_to_end(&mut bytes).map_err(io)?;
    parse(&bytes)
}

/// What a path that is not a regular file is, for the error message.
fn file_kind(file_type: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if file_type.is_char_device() {
            return "a character device";
        } else if file_type.is_block_device() {
            return "a block device";
        } else if file_type.is_fifo() {
            return "a pipe";
        } else if file_type.is_socket() {
            return "a socket";
        }
    }
    if file_type.is_dir() { "a directory" } else { "not a file" }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_points_become_invalid_in_organized_clouds() {
        let cloud = PointCloud::organized(2, 1, vec![[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]).unwrap();
        assert!(cloud.points()[0][0].is_nan());
        assert_eq!(cloud.valid_count(), 1);
        assert!(!cloud.is_organized(), "a single row is not a grid");
    }

    #[test]
    fn unorganized_clouds_drop_invalid_points() {
        let cloud = PointCloud::unorganized(vec![[f32::NAN, 0.0, 1.0], [1.0, 2.0, 3.0], [0.0, 0.0, 0.0]]);
        assert_eq!(cloud.len(), 1);
    }

    #[test]
    fn large_files_are_mapped_and_decode_as_read_ones_do() {
        let (w, h) = (320, 300);
        let points = (0..w * h).map(|i| [(i % w) as f32 * 0.2, (i / w) as f32 * 0.2, 500.0 + (i % 7) as f32]).collect();
        let cloud = PointCloud::organized(w, h, points).unwrap();
        let mut bytes = Vec::new();
        pcd::write_binary(&cloud, &mut bytes).unwrap();
        assert!(bytes.len() as u64 >= MAP_FROM_BYTES, "the file takes the mapped path");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frame.pcd");
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(load(&path).unwrap(), cloud);
        // A file cut short before loading is a data error, mapped or not.
        std::fs::write(&path, &bytes[..bytes.len() - 5000]).unwrap();
        let err = load(&path).unwrap_err();
        assert!(matches!(err, LoadError::Data { .. }), "{err}");
    }

    #[test]
    #[cfg(unix)]
    fn devices_and_directories_are_refused_unread() {
        let dir = tempfile::tempdir().unwrap();
        let zero = dir.path().join("zero.pcd");
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
        let folder = dir.path().join("folder.ply");
        std::fs::create_dir(&folder).unwrap();
        let pipe = dir.path().join("pipe.pcd");
        let name = std::ffi::CString::new(pipe.as_os_str().as_encoded_bytes()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo only creates the node.
        assert_eq!(unsafe { libc::mkfifo(name.as_ptr(), 0o600) }, 0, "mkfifo");
        for (path, kind) in [(zero, "a character device"), (folder, "a directory"), (pipe, "a pipe")] {
            // Opening a pipe without a writer blocks: load must refuse it
            // unopened, so a hang here is a failure, not a wait.
            let (tx, rx) = std::sync::mpsc::channel();
            let target = path.clone();
            std::thread::spawn(move || tx.send(load(&target).map(|_| ())));
            let outcome = rx.recv_timeout(std::time::Duration::from_secs(10));
            let err = outcome.unwrap_or_else(|_| panic!("{kind}: load did not return")).unwrap_err();
            assert!(matches!(err, LoadError::NotAFile { .. }), "{err}");
            assert_eq!(err.to_string(), format!("{} is {kind}, not a regular file", path.display()));
        }
    }

    #[test]
    fn organized_rejects_wrong_length() {
        assert!(PointCloud::organized(3, 2, vec![[1.0, 1.0, 1.0]; 5]).is_none());
        assert!(PointCloud::organized(usize::MAX, 2, vec![]).is_none());
    }
}
