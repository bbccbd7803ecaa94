//! Which spelling the arguments of `rbc-sweep` use: a subcommand ([`crate::cli`]) when the first argument names one (or asks for help or the version), otherwise the old flag spelling ([`crate::legacy`]); how parsing stops without a command.

use crate::cli::{Cli, Cmd};
use crate::legacy::LegacyArgs;
use clap::{CommandFactory, FromArgMatches, Parser};
use std::ffi::OsString;
use std::path::Path;

/// How parsing ended without a command: help/version printed (exit 0), or an error to report
/// on one line (exit 2).
pub enum Stop {
    Printed(clap::Error),
    Input(String),
}

/// The subcommand names, as the first argument.
fn subcommand_names() -> Vec<String> {
    Cli::command().get_subcommands().map(|c| c.get_name().to_string()).collect()
}

/// Parse the arguments (`argv[0]` is the program): the subcommand spelling when the first
/// argument names a subcommand (or asks for help/version), otherwise the old flag spelling. A
/// bare word that is no subcommand, no file and no path is an unknown subcommand.
pub fn parse(argv: &[OsString]) -> Result<Cmd, Stop> {
    let names = subcommand_names();
    let Some(first) = argv.get(1) else {
        return Err(Stop::Input(format!(
            "missing a subcommand ({}); see rbc-sweep --help",
            names.join(", ")
        )));
    };
    let first_str = first.to_string_lossy();
    let new_spelling = names.iter().any(|n| *n == first_str)
        || matches!(&*first_str, "help" | "--help" | "-h" | "--version" | "-V");
    if new_spelling {
        return Cli::try_parse_from(argv).map(|c| c.cmd).map_err(clap_stop);
    }
    let bare_word = !first_str.starts_with('-') && !first_str.contains(['.', '/']);
    if bare_word && !Path::new(first).exists() {
        return Err(Stop::Input(format!(
            "unknown subcommand `{first_str}` (one of {}; or a sweep file first, the old spelling)",
            names.join(", ")
        )));
    }
    let matches = LegacyArgs::command().try_get_matches_from(argv).map_err(clap_stop)?;
    let args = LegacyArgs::from_arg_matches(&matches).map_err(clap_stop)?;
    args.into_cmd().map_err(|e| Stop::Input(format!("{e:#}")))
}

/// A clap error as a `Stop`: help and version texts are printed as clap formats them, an error
/// becomes one line (its message and tips, without the usage block).
fn clap_stop(e: clap::Error) -> Stop {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
        return Stop::Printed(e);
    }
    let text = e.render().to_string();
    let line = text
        .lines()
        .take_while(|l| !l.starts_with("Usage:"))
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    Stop::Input(line.trim_start_matches("error: ").to_string())
}
