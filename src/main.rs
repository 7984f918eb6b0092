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
    // Exit codes: 0 success; 2 the run finished and wrote its record but
    // did not reach its goal (`"outcome": "goal_not_met"`); 1 any other
    // failure (bad input, a solve that found no answer: no record).
    if let Err(e) = softrod_cli::run() {
        if let Some(g) = e.downcast_ref::<softrod_cli::output::GoalNotMet>() {
            eprintln!("softrod: goal not met: {g}");
            std::process::exit(softrod_cli::output::EXIT_GOAL_NOT_MET);
        }
        eprintln!("softrod: error: {e:#}");
        std::process::exit(1);
    }
}

#[path = "cli/mod.rs"]
mod softrod_cli;
