//! The `softrod` command line. See `softrod --help`.

fn main() {
    // Every failure is one line on stderr and a non-zero exit: the library
    // returns errors, and should anything still panic, the hook reports it
    // in one line instead of a backtrace.
    std::panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        eprintln!(
            "softrod: internal error: {} (please report this)",
            msg.split_whitespace().collect::<Vec<_>>().join(" ")
        );
    }));
    if let Err(e) = softrod_cli::run() {
        eprintln!("softrod: error: {e:#}");
        std::process::exit(1);
    }
}

#[path = "cli/mod.rs"]
mod softrod_cli;
