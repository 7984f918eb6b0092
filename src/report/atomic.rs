//! Atomic output: every file the report and the command line write goes
//! through [`write_atomic`] (or `with_temp`, crate-internal, for a chart drawn by a
//! backend that opens its own file), so a reader polling the file (a
//! plotting script, a controller that reloads `--out`) sees the old content
//! or the new one, never an empty or partial file.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::error::Result;

/// Writes `bytes` to `path` atomically: into a new temporary file in the
/// same directory (`.STEM.PID.N.tmp.EXT`, so the rename stays on one file
/// system), flushed to disk, then renamed over `path`. On any failure the
/// temporary file is removed and `path` is left as it was.
///
/// # Errors
/// [`Error::Io`](crate::Error::Io) naming `path`.
///
/// # Example
/// ```
/// let path = std::env::temp_dir().join(format!("softrod-doc-{}.json", std::process::id()));
/// softrod::report::atomic::write_atomic(&path, b"{}\n")?;
/// assert_eq!(std::fs::read(&path)?, b"{}\n");
/// # std::fs::remove_file(&path)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    with_temp(path, |tmp| {
        let written = (|| -> std::io::Result<()> {
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(tmp)?;
            f.write_all(bytes)?;
            f.sync_all()
        })();
        written.map_err(|e| super::io_error(path, e))
    })
}

/// Runs `write` on a fresh temporary path beside `path` (the same
/// directory and extension), then renames the temporary file over `path`;
/// if `write` or the rename fails, the temporary file is removed and
/// `path` is left as it was.
///
/// # Errors
/// `write`'s error; [`Error::Io`](crate::Error::Io) naming `path` if the rename fails.
pub(crate) fn with_temp(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = temp_path(path)?;
    let done = write(&tmp)
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| super::io_error(path, e)));
    if done.is_err() {
        // the temporary file is ours; the target is untouched
        let _ = std::fs::remove_file(&tmp);
    }
    done
}

/// A fresh temporary name beside `path` (the same directory, the same
/// extension: plotters picks a bitmap's format by it).
fn temp_path(path: &Path) -> Result<PathBuf> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let stem = path
        .file_stem()
        .ok_or_else(|| super::io_error(path, "not a file name"))?;
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let tmp = format!(
        ".{}.{}.{n}.tmp{ext}",
        stem.to_string_lossy(),
        std::process::id()
    );
    Ok(path.with_file_name(tmp))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("softrod-atomic-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A reader polling the file while it is rewritten 200 times (1 MiB
    /// each, two alternating contents) only ever sees one of the two whole
    /// contents; afterwards the directory holds the target alone (no
    /// temporary left). With `std::fs::write` (truncate, then write) the
    /// reader sees empty or partial files.
    #[test]
    fn a_polling_reader_never_sees_a_partial_file() {
        let dir = scratch("poll");
        let path = dir.join("out.json");
        let a = vec![b'a'; 1 << 20];
        let b = vec![b'b'; 1 << 20];
        write_atomic(&path, &a).unwrap();
        let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let reader = {
            let (path, done) = (path.clone(), done.clone());
            let (a, b) = (a.clone(), b.clone());
            std::thread::spawn(move || {
                let (mut reads, mut bad) = (0usize, 0usize);
                while !done.load(std::sync::atomic::Ordering::Relaxed) {
                    let got = std::fs::read(&path).unwrap();
                    reads += 1;
                    if got != a && got != b {
                        bad += 1;
                    }
                }
                (reads, bad)
            })
        };
        for i in 0..200 {
            write_atomic(&path, if i % 2 == 0 { &b } else { &a }).unwrap();
        }
        done.store(true, std::sync::atomic::Ordering::Relaxed);
        let (reads, bad) = reader.join().unwrap();
        assert!(reads > 0);
        assert_eq!(bad, 0, "{bad} of {reads} reads saw a partial file");
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left, vec![std::ffi::OsString::from("out.json")]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The temporary file is a sibling of the target (same directory, so
    /// the rename is atomic), hidden and unique per call.
    #[test]
    fn the_temporary_file_is_in_the_target_directory() {
        let p = Path::new("/some/dir/result.json");
        let (t1, t2) = (temp_path(p).unwrap(), temp_path(p).unwrap());
        assert_eq!(t1.parent(), p.parent());
        assert_ne!(t1, t2);
        let name = t1.file_name().unwrap().to_string_lossy().into_owned();
        // hidden, and the extension kept (plotters picks the image format by it)
        assert!(
            name.starts_with(".result.") && name.ends_with(".tmp.json"),
            "{name}"
        );
    }

    /// A drawing written through `with_temp` lands whole under its own name
    /// (a PNG keeps its extension while it is drawn), and a failed one
    /// leaves the old file.
    #[test]
    fn with_temp_renames_on_success_only() {
        let dir = scratch("temp");
        let path = dir.join("chart.png");
        with_temp(&path, |tmp| {
            assert!(tmp.to_string_lossy().ends_with(".png"));
            std::fs::write(tmp, b"new").map_err(|e| crate::report::io_error(tmp, e))
        })
        .unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        let e = with_temp(&path, |tmp| {
            std::fs::write(tmp, b"partial").unwrap();
            Err(crate::report::io_error(tmp, "drawing failed"))
        });
        assert!(e.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A failed write (a missing directory) leaves nothing behind and names the target.
    #[test]
    fn a_failed_write_names_the_target_and_leaves_no_temporary() {
        let dir = scratch("fail");
        let path = dir.join("missing").join("out.json");
        let err = write_atomic(&path, b"x").unwrap_err();
        assert!(err.to_string().contains("missing/out.json"), "{err}");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
