//! Command-line parsing shared by the subcommands.

/// Options that take no value.
pub const FLAGS: [&str; 2] = ["no-shared", "big"];

/// Positional arguments and `--key value` pairs.
pub type Parsed = (Vec<String>, Vec<(String, String)>);

/// Splits `--key value` options (and the value-less [`FLAGS`]) from positional arguments.
pub fn options(args: &[String]) -> Result<Parsed, String> {
    let (mut pos, mut opts) = (Vec::new(), Vec::new());
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if let Some(k) = a.strip_prefix("--") {
            if FLAGS.contains(&k) {
                opts.push((k.to_string(), String::new()));
                continue;
            }
            let v = it.next().ok_or_else(|| format!("--{k} needs a value"))?;
            opts.push((k.to_string(), v.clone()));
        } else {
            pos.push(a.clone());
        }
    }
    Ok((pos, opts))
}

/// The last value given for `--key`.
pub fn opt<'a>(opts: &'a [(String, String)], key: &str) -> Option<&'a str> {
    opts.iter()
        .rev()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

/// `s` parsed, or an error naming `what`.
pub fn parse<T: std::str::FromStr>(s: &str, what: &str) -> Result<T, String> {
    s.parse().map_err(|_| format!("bad {what}: {s}"))
}

/// A comma-separated list (empty items skipped).
pub fn list<T: std::str::FromStr>(s: &str, what: &str) -> Result<Vec<T>, String> {
    s.split(',')
        .filter(|x| !x.is_empty())
        .map(|x| parse(x, what))
        .collect()
}
