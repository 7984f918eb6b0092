//! The `softrod` command line. See `softrod --help`.

fn main() {
    if let Err(e) = softrod_cli::run() {
        eprintln!("softrod: error: {e:#}");
        std::process::exit(1);
    }
}

mod softrod_cli {
    include!("cli.rs");
}
