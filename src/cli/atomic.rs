// Atomic output: every file the command line writes goes through
// `write_atomic`, so a reader polling the file (a plotting script, a
// controller that reloads `--out`) sees the old content or the new one,
// never an empty or partial file.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// Writes `bytes` to `path` atomically: into a new temporary file in the
/// same directory (`.NAME.PID.N.tmp`, so the rename stays on one file
/// system), flushed to disk, then renamed over `path`. On any failure the
/// temporary file is removed and `path` is left as it was.
pub(super) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = temp_path(path)?;
    let written = (|| -> std::io::Result<()> {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    written.map_err(|e| {
        // the temporary file is ours; the target is untouched
        let _ = std::fs::remove_file(&tmp);
        anyhow::Error::new(e).context(format!("cannot write {}", path.display()))
    })
}

/// A fresh temporary name beside `path` (the same directory).
fn temp_path(path: &Path) -> Result<PathBuf> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let name = path
        .file_name()
        .with_context(|| format!("cannot write {}: not a file name", path.display()))?;
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = format!(".{}.{}.{n}.tmp", name.to_string_lossy(), std::process::id());
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
        assert!(t1
            .file_name()
            .unwrap()
            .to_string_lossy()
            .starts_with(".result.json."));
    }

    /// A failed write (a missing directory) leaves nothing behind and names the target.
    #[test]
    fn a_failed_write_names_the_target_and_leaves_no_temporary() {
        let dir = scratch("fail");
        let path = dir.join("missing").join("out.json");
        let err = write_atomic(&path, b"x").unwrap_err();
        assert!(format!("{err:#}").contains("missing/out.json"), "{err:#}");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
