//! What the `vkpt` and `vkpt bench` argument parsers share: `--flag value`
//! and `--flag=value` spellings, and numbers with a message naming the flag.

use anyhow::anyhow;

/// Splits `--flag=value` into the flag and its inline value.
pub fn split_flag(arg: &str) -> (&str, Option<String>) {
    match arg.split_once('=') {
        Some((f, v)) if f.starts_with("--") => (f, Some(v.to_string())),
        _ => (arg, None),
    }
}

/// The flag's value: inline, else the next argument.
pub fn flag_value(
    flag: &str,
    inline: &Option<String>,
    rest: &mut std::slice::Iter<String>,
    help: &str,
) -> anyhow::Result<String> {
    inline
        .clone()
        .or_else(|| rest.next().cloned())
        .ok_or_else(|| anyhow!("{flag} needs a value (see {help})"))
}

pub fn parse_number<T: std::str::FromStr>(flag: &str, value: &str) -> anyhow::Result<T> {
    value
        .parse()
        .map_err(|_| anyhow!("{flag} expects a number, got '{value}'"))
}
