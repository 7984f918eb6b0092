// Atomic output of the command line: `softrod::report::atomic`, its error
// in the command line's form.

use std::path::Path;

use anyhow::Result;

/// Writes `bytes` to `path` atomically (see `softrod::report::atomic`).
pub(super) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    softrod::report::atomic::write_atomic(path, bytes)
        .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))
}
