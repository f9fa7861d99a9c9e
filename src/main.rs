//! The `brdf-shop` binary: parses the command line (README, Commands) and turns every error into one line on
//! stderr with exit status 1 (the user's input) or 2 (internal or device), never a panic.

// `!(x > 0.0)` is how this code says "not a positive number, NaN included"; the lint would
// have it written `x <= 0.0`, which lets NaN through. Per-channel `for c in 0..3` loops read
// better than zipped iterators over three arrays.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    brdf_shop::fsio::ignore_relative_xdg();
    let cli = match cli::parse() {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    match cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<cli::NotPhysicallyCorrect>().is_some() => ExitCode::from(3),
        Err(e) if e.downcast_ref::<brdf_shop::interrupt::Interrupted>().is_some() => {
            eprintln!("brdf-shop: {e}");
            ExitCode::from(brdf_shop::interrupt::EXIT_STATUS)
        }
        Err(e) => {
            let user = e.chain().any(|c| c.downcast_ref::<brdf_shop::Error>().is_some_and(|e| e.is_user_error()))
                || e.downcast_ref::<cli::UsageError>().is_some();
            // Each cause once: `{e:#}` repeats a source that its error already displays
            // (`path: reason: reason`).
            let mut msg = String::new();
            for cause in e.chain() {
                let text = cause.to_string();
                if !msg.ends_with(&text) {
                    if !msg.is_empty() {
                        msg.push_str(": ");
                    }
                    msg.push_str(&text);
                }
            }
            eprintln!("brdf-shop: {}", cli::tidy_message(&msg));
            ExitCode::from(if user { 1 } else { 2 })
        }
    }
}
