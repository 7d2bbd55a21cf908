//! The tool's errors: one line on stderr, and status 2.

use std::ffi::OsString;

use clap::error::ErrorKind;

pub use imu_ar_recordings::error::{Fail, escaped, with_file};

/// A command-line error of `command`, parsed from `args`, as one line: clap's message and
/// details (the missing arguments, a tip) without the usage and the pointer to `--help`;
/// for no arguments at all, the subcommands; for an argument that is not UTF-8, which one.
pub fn clap_error(e: &clap::Error, command: &clap::Command, args: &[OsString]) -> String {
    let msg = match e.kind() {
        // The help shown for no arguments at all.
        ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let names: Vec<&str> = command.get_subcommands().map(|c| c.get_name()).collect();
            format!(
                "a subcommand is required ({}); see imu-ar --help",
                names.join(", ")
            )
        }
        ErrorKind::InvalidUtf8 => clap_message(&e.to_string()) + &not_utf8(args),
        _ => clap_message(&e.to_string()),
    };
    escaped(&msg)
}

/// A clap error's text as one line: its message and details, without the usage and the
/// pointer to `--help`.
fn clap_message(text: &str) -> String {
    let mut msg = String::new();
    // Whether the lines are the items of a list ("...not provided:" and the arguments).
    let mut list = false;
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with("Usage:") {
            break;
        }
        if line.is_empty() {
            list = false;
            continue;
        }
        if line.starts_with("For more information") {
            continue;
        }
        let line = line.trim_start_matches("error: ");
        if msg.ends_with(':') {
            msg += " ";
            list = true;
        } else if list {
            msg += ", ";
        } else if !msg.is_empty() {
            msg += "; ";
        }
        msg += line;
    }
    if msg.is_empty() {
        "invalid arguments".into()
    } else {
        msg
    }
}

/// Which of `args` (the program's name first) is not UTF-8, for clap's error that does not
/// say: `: argument 4 ('g�x', after '--column')` (`�` for the bytes that are not UTF-8).
fn not_utf8(args: &[OsString]) -> String {
    let Some(i) = args.iter().skip(1).position(|a| a.to_str().is_none()) else {
        return String::new();
    };
    let shown = args[i + 1].to_string_lossy();
    match i {
        0 => format!(": argument 1 ('{shown}')"),
        _ => format!(
            ": argument {} ('{shown}', after '{}')",
            i + 1,
            args[i].to_string_lossy()
        ),
    }
}
