//! The `brdf-shop` binary: parses the command line (README, Commands) and turns every error into one line on
//! stderr and an exit status that says its kind ([`exit_status`]), never a panic.

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
    let result = match failure_on_request() {
        Some(e) => Err(e.into()),
        None => cli::run(cli),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The verdict was printed with the report.
        Err(e) if e.downcast_ref::<cli::NotPhysicallyCorrect>().is_some() => ExitCode::from(exit_status(&e)),
        Err(e) => {
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
            ExitCode::from(exit_status(&e))
        }
    }
}

/// The variable that debug builds read in [`failure_on_request`].
const FAIL_ENV: &str = "BRDF_SHOP_FAIL";

/// Debug builds only: `BRDF_SHOP_FAIL=bug|validation|system` ends the command before it runs with a
/// library error of that kind (an internal invariant broken, a validation-layer message, a thread
/// the system refused), so that tests/cli.rs checks through the whole binary the line and the exit
/// status each kind ends with. Release builds read no such variable.
fn failure_on_request() -> Option<brdf_shop::Error> {
    use brdf_shop::Error;
    if !cfg!(debug_assertions) {
        return None;
    }
    Some(match std::env::var(FAIL_ENV).ok()?.as_str() {
        "bug" => Error::Bug(format!("an invariant broken on request ({FAIL_ENV})")),
        "validation" => Error::Validation(format!("a validation error on request ({FAIL_ENV})")),
        "system" => Error::System {
            what: "cannot start a thread on request (BRDF_SHOP_FAIL)",
            source: std::io::ErrorKind::WouldBlock.into(),
        },
        _ => return None,
    })
}

/// The exit status of a command that failed with `e`: `check`'s verdict, Ctrl-C and a mistake on
/// the command line have their own; a library error, the status of its kind
/// ([`brdf_shop::Error::exit_status`]: 1 the user's input, 2 the device, driver or system,
/// 4 validation, 5 a bug); an error of the binary's own (encoding an output, creating the demo's
/// folder), 2.
fn exit_status(e: &anyhow::Error) -> u8 {
    use brdf_shop::error::{EXIT_SYSTEM, EXIT_USER};
    if e.downcast_ref::<cli::NotPhysicallyCorrect>().is_some() {
        cli::NotPhysicallyCorrect::EXIT_STATUS
    } else if e.downcast_ref::<brdf_shop::interrupt::Interrupted>().is_some() {
        brdf_shop::interrupt::EXIT_STATUS
    } else if e.downcast_ref::<cli::UsageError>().is_some() {
        EXIT_USER
    } else {
        e.chain().find_map(|c| c.downcast_ref::<brdf_shop::Error>()).map_or(EXIT_SYSTEM, brdf_shop::Error::exit_status)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context as _;
    use brdf_shop::error::{EXIT_BUG, EXIT_SYSTEM, EXIT_USER, EXIT_VALIDATION};
    use brdf_shop::Error;

    #[test]
    fn each_failure_has_its_status_through_context() {
        let cases: [(anyhow::Error, u8); 9] = [
            (cli::NotPhysicallyCorrect.into(), 3),
            (brdf_shop::interrupt::Interrupted.into(), 130),
            (cli::UsageError("--size: not a number".into()).into(), EXIT_USER),
            (Error::input("m.brdf.json", "bad").into(), EXIT_USER),
            (Error::NoDevice("no Vulkan 1.3 driver".into()).into(), EXIT_SYSTEM),
            (Error::Validation("1 validation error(s)".into()).into(), EXIT_VALIDATION),
            (Error::Bug("a frame was begun twice".into()).into(), EXIT_BUG),
            // Wrapped in the binary's context: the library error's kind still decides.
            (Err::<(), _>(Error::Bug("no mesh view was rendered".into())).context("render").unwrap_err(), EXIT_BUG),
            (anyhow::anyhow!("encoding JSON"), EXIT_SYSTEM),
        ];
        for (e, want) in &cases {
            assert_eq!(exit_status(e), *want, "{e:#}");
        }
    }

    #[test]
    fn the_binarys_statuses_are_distinct() {
        let all = [
            EXIT_USER,
            EXIT_SYSTEM,
            cli::NotPhysicallyCorrect::EXIT_STATUS,
            EXIT_VALIDATION,
            EXIT_BUG,
            brdf_shop::interrupt::EXIT_STATUS,
        ];
        for (i, a) in all.iter().enumerate() {
            assert!(*a != 0 && !all[i + 1..].contains(a), "{all:?}");
        }
    }
}
