//! Log output for every subcommand: tracing to stderr, human-readable or
//! JSON lines for log shippers, filtered RUST_LOG-style (by default `warn`
//! for one-shot commands and `info` for the daemon and the mock camera).
//! Stdout stays free for command output such as `plan --json`.

use std::io::IsTerminal;

use tracing_subscriber::EnvFilter;

/// How log lines are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum LogFormat {
    #[default]
    Text,
    Json,
}

/// Installs the global subscriber. `default_level` applies when RUST_LOG
/// is unset.
pub fn init(format: LogFormat, default_level: &str) -> anyhow::Result<()> {
    let filter = EnvFilter::try_from_default_env().or_else(|_| EnvFilter::try_new(default_level))?;
    // Colour codes only for a person at a terminal: in a file, a pipe or a
    // journal they are noise around every level name.
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal());
    let result = match format {
        LogFormat::Text => builder.try_init(),
        LogFormat::Json => builder.json().try_init(),
    };
    result.map_err(|e| anyhow::anyhow!("cannot install the logger: {e}"))
}
