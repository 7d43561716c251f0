//! USD identifiers: sanitizing names and making sibling names unique.

use std::collections::HashSet;

/// Turns `name` into a valid USD identifier (`[A-Za-z_][A-Za-z0-9_]*`): every other character
/// (including non-ASCII ones) becomes `_`, a leading digit gets a `_` prefix, and an empty name
/// becomes `_`.
///
/// ```
/// use tessd_usd::sanitize_identifier;
/// assert_eq!(sanitize_identifier("Material.001"), "Material_001");
/// assert_eq!(sanitize_identifier("3D part"), "_3D_part");
/// assert_eq!(sanitize_identifier(""), "_");
/// ```
pub fn sanitize_identifier(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

/// Hands out unique sanitized names among siblings: `a`, `a_1`, `a_2`...
#[derive(Default)]
pub(crate) struct UniqueNames {
    used: HashSet<String>,
}

impl UniqueNames {
    /// The sanitized form of `name` (or of `fallback` when `name` is empty), suffixed with `_n`
    /// if a sibling already took it.
    pub(crate) fn claim(&mut self, name: &str, fallback: &str) -> String {
        let base = sanitize_identifier(if name.is_empty() { fallback } else { name });
        let mut candidate = base.clone();
        let mut n = 1u64;
        while self.used.contains(&candidate) {
            candidate = format!("{base}_{n}");
            n += 1;
        }
        self.used.insert(candidate.clone());
        candidate
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sanitizes() {
        assert_eq!(sanitize_identifier("Cube"), "Cube");
        assert_eq!(sanitize_identifier("my mat/1"), "my_mat_1");
        assert_eq!(sanitize_identifier("Würfel"), "W_rfel");
        assert_eq!(sanitize_identifier("007"), "_007");
        assert_eq!(sanitize_identifier("_x9"), "_x9");
        assert_eq!(sanitize_identifier(""), "_");
    }

    #[test]
    fn dedupes_siblings() {
        let mut u = UniqueNames::default();
        assert_eq!(u.claim("a", "g"), "a");
        assert_eq!(u.claim("a", "g"), "a_1");
        assert_eq!(u.claim("a.", "g"), "a_");
        assert_eq!(u.claim("a", "g"), "a_2");
        assert_eq!(u.claim("a_1", "g"), "a_1_1");
        assert_eq!(u.claim("", "g"), "g");
        assert_eq!(u.claim("", "g"), "g_1");
    }
}
