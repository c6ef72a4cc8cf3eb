//! The `vkpt` command: `vkpt SCENE` renders, `vkpt compare` and `vkpt bench`
//! test and measure, `vkpt merge` joins the parts of a split render. Try: `vkpt scenes/cornell-box.gltf --spp 64 -o cornell.png`

mod args;
mod bench_command;
mod compare_command;
mod errors;
mod interrupt;
mod merge_command;
mod progress;
mod render_command;
mod sequence_command;

use args::{Cli, Command};
use clap::Parser as _;

fn main() {
    // Piped into `head` or `less`: end quietly when the reader goes away,
    // as command-line tools do, instead of panicking on a failed print.
    // SAFETY: restores the default action before any thread starts.
    unsafe { libc::signal(libc::SIGPIPE, libc::SIG_DFL) };
    // lavapipe as one single-threaded device per core (vkpt::gpu::split).
    // SAFETY: no other thread has started.
    if let Err(e) = unsafe { vkpt::gpu::split::configure_process() } {
        errors::print_error(&e);
        std::process::exit(2);
    }
    let cli = Cli::parse();
    let code = match cli.command {
        Some(Command::Compare(a)) => match compare_command::run(&a) {
            Ok(true) => 0,
            Ok(false) => 1,
            Err(e) => {
                errors::print_error(&e);
                2
            }
        },
        Some(Command::Bench(a)) => match bench_command::run(a) {
            Ok(()) => 0,
            Err(e) => {
                errors::print_error(&e);
                1
            }
        },
        Some(Command::Merge(a)) => match merge_command::run(&a) {
            Ok(()) => 0,
            Err(e) => {
                errors::print_error(&e);
                1
            }
        },
        None => match render_command::run(cli.render) {
            Ok(code) => code,
            Err(e) => {
                errors::print_error(&e);
                1
            }
        },
    };
    std::process::exit(code);
}
