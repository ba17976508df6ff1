//! Project chores: `cargo xtask <command>`.
use clap::Parser;

#[derive(Parser)]
#[command(name = "xtask", about = "wfem project chores")]
enum Cmd {
    /// Print the version of the workspace.
    Version,
}

fn main() {
    match Cmd::parse() {
        Cmd::Version => println!("wfem xtask {}", env!("CARGO_PKG_VERSION")),
    }
}
