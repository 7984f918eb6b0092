//! JSON parsing with the path of the field at fault, for every input file
//! of the crate (scenes, parallel scenes, avoidance and grasp scenes,
//! trajectory, payload and markers files).
//!
//! `serde_path_to_error` follows the deserializer, but an internally tagged
//! enum (`{"type": "tip_force", "force_n": [...]}`) is buffered before its
//! variant is known and deserialized again from the buffer, outside the
//! tracked deserializer: an error inside it names only the enum's own
//! position (`loads[0]`). [`parse`] then finds the field inside that object
//! from the error itself (the missing, unknown or mistyped value it names)
//! and, when several values fit, by re-parsing with each candidate replaced.

use serde::de::DeserializeOwned;
use serde_json::Value;

/// Why a JSON text could not be deserialized: the path of the field at
/// fault as the user wrote it (`loads[0].force_n[1]`; empty for the whole
/// file) and serde's message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ParseFailure {
    /// The field's path (`robot.sections[0].length_m`), empty for the file.
    pub path: String,
    /// What is wrong (serde's message, with line and column).
    pub message: String,
}

impl ParseFailure {
    /// `path: message`, or the message alone for the whole file.
    pub(crate) fn located(&self) -> String {
        if self.path.is_empty() {
            self.message.clone()
        } else {
            format!("{}: {}", self.path, self.message)
        }
    }

    /// The path, or `(file)` for the whole file.
    pub(crate) fn name(&self) -> String {
        if self.path.is_empty() {
            "(file)".to_string()
        } else {
            self.path.clone()
        }
    }
}

/// Deserializes `text` as `T`; on failure, the path of the field at fault
/// (inside internally tagged enums too, see the [module documentation](self)).
pub(crate) fn parse<T: DeserializeOwned>(text: &str) -> std::result::Result<T, ParseFailure> {
    let (path, message) = match try_parse::<T>(text) {
        Ok(v) => return Ok(v),
        Err(e) => e,
    };
    // a syntax error, or a file that is not JSON: the parser's path stands
    let Ok(doc) = serde_json::from_str::<Value>(text) else {
        return Err(ParseFailure { path, message });
    };
    // a custom deserializer inside a tagged enum may start its message with
    // the path below it (`moment_nm[0]: invalid type ...`): join the two
    let (path, message) = match message.split_once(": ") {
        Some((head, rest))
            if !head.contains(' ')
                && !parse_path(head).is_empty()
                && lookup(&doc, &[parse_path(&path), parse_path(head)].concat()).is_some() =>
        {
            (show(&path, &parse_path(head)), rest.to_string())
        }
        _ => (path, message),
    };
    let steps = parse_path(&path);
    let refined = match lookup(&doc, &steps) {
        Some(v @ (Value::Object(_) | Value::Array(_))) => {
            refine::<T>(&doc, &steps, v, &path, &message).unwrap_or(path)
        }
        _ => path,
    };
    Err(ParseFailure {
        path: refined,
        message,
    })
}

/// One attempt: the tracked path (without the `?` of unidentified
/// segments) and the message. Text after the value (anything but
/// whitespace) is an error of the whole file, as in `serde_json::from_str`:
/// a scene followed by more text is not the scene.
fn try_parse<T: DeserializeOwned>(text: &str) -> std::result::Result<T, (String, String)> {
    let de = &mut serde_json::Deserializer::from_str(text);
    let value = serde_path_to_error::deserialize(&mut *de).map_err(|e| {
        let path = e.path().to_string();
        let path = path.trim_end_matches(".?").trim_end_matches('?');
        let path = if path == "." { "" } else { path }.to_string();
        (path, e.into_inner().to_string())
    })?;
    de.end().map_err(|e| (String::new(), e.to_string()))?;
    Ok(value)
}

/// A step of a path: a key or an index.
#[derive(Debug, Clone, PartialEq)]
enum Step {
    Key(String),
    Index(usize),
}

/// `a.b[2].c` as steps (the format of `serde_path_to_error`).
fn parse_path(path: &str) -> Vec<Step> {
    let mut steps = Vec::new();
    for part in path.split('.').filter(|p| !p.is_empty()) {
        let (key, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if !key.is_empty() {
            steps.push(Step::Key(key.to_string()));
        }
        while let Some(end) = rest.find(']') {
            if let Ok(i) = rest[1..end].parse() {
                steps.push(Step::Index(i));
            }
            rest = &rest[end + 1..];
        }
    }
    steps
}

fn lookup<'a>(v: &'a Value, steps: &[Step]) -> Option<&'a Value> {
    steps.iter().try_fold(v, |v, s| match s {
        Step::Key(k) => v.get(k.as_str()),
        Step::Index(i) => v.get(*i),
    })
}

fn lookup_mut<'a>(v: &'a mut Value, steps: &[Step]) -> Option<&'a mut Value> {
    steps.iter().try_fold(v, |v, s| match s {
        Step::Key(k) => v.get_mut(k.as_str()),
        Step::Index(i) => v.get_mut(*i),
    })
}

/// `base` extended by the relative steps, in the user's notation.
fn show(base: &str, rel: &[Step]) -> String {
    let mut out = base.to_string();
    for s in rel {
        match s {
            Step::Key(k) if out.is_empty() => out.push_str(k),
            Step::Key(k) => {
                out.push('.');
                out.push_str(k);
            }
            Step::Index(i) => out.push_str(&format!("[{i}]")),
        }
    }
    out
}

/// The text between the first pair of backticks after `prefix` in `m`.
fn quoted_after<'a>(m: &'a str, prefix: &str) -> Option<&'a str> {
    let rest = m.strip_prefix(prefix)?;
    let rest = rest.strip_prefix('`')?;
    rest.find('`').map(|e| &rest[..e])
}

/// The field inside `v` (the object at `path`) that the message `m` is
/// about, as a full path; `None` if it cannot be told.
fn refine<T: DeserializeOwned>(
    doc: &Value,
    steps: &[Step],
    v: &Value,
    path: &str,
    m: &str,
) -> Option<String> {
    if let Some(field) = quoted_after(m, "missing field ") {
        // the object at the path itself, if it lacks the field; else an
        // object inside it (a tagged enum buffers its whole content)
        if v.as_object().is_some_and(|o| !o.contains_key(field)) {
            return Some(show(path, &[Step::Key(field.to_string())]));
        }
        let mut objects = Vec::new();
        descend(v, &mut Vec::new(), &mut |rel, x| {
            if x.as_object().is_some_and(|o| !o.contains_key(field)) {
                objects.push(rel.to_vec());
            }
        });
        return pick::<T>(doc, steps, path, m, objects)
            .map(|rel| show(path, &[rel, vec![Step::Key(field.to_string())]].concat()));
    }
    if let Some(field) =
        quoted_after(m, "unknown field ").or_else(|| quoted_after(m, "duplicate field "))
    {
        let mut found = Vec::new();
        descend(v, &mut Vec::new(), &mut |rel, x| {
            if x.as_object().is_some_and(|o| o.contains_key(field)) {
                let mut r = rel.to_vec();
                r.push(Step::Key(field.to_string()));
                found.push(r);
            }
        });
        return pick::<T>(doc, steps, path, m, found).map(|rel| show(path, &rel));
    }
    if let Some(variant) = quoted_after(m, "unknown variant ") {
        let mut found = Vec::new();
        descend(v, &mut Vec::new(), &mut |rel, x| {
            if x.as_str() == Some(variant) && !rel.is_empty() {
                found.push(rel.to_vec());
            }
        });
        return pick::<T>(doc, steps, path, m, found).map(|rel| show(path, &rel));
    }
    let matches = unexpected_matcher(m)?;
    let mut found = Vec::new();
    descend(v, &mut Vec::new(), &mut |rel, x| {
        if !rel.is_empty() && matches(x) {
            found.push(rel.to_vec());
        }
    });
    // the deepest: a container whose element was reached was itself accepted
    let deepest: Vec<Vec<Step>> = found
        .iter()
        .filter(|a| {
            !found
                .iter()
                .any(|b| b.len() > a.len() && b[..a.len()] == a[..])
        })
        .cloned()
        .collect();
    pick::<T>(doc, steps, path, m, deepest).map(|rel| show(path, &rel))
}

/// Calls `f` on `v` and every value inside it with its relative path.
fn descend(v: &Value, rel: &mut Vec<Step>, f: &mut dyn FnMut(&[Step], &Value)) {
    f(rel, v);
    match v {
        Value::Object(o) => {
            for (k, x) in o {
                rel.push(Step::Key(k.clone()));
                descend(x, rel, f);
                rel.pop();
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                rel.push(Step::Index(i));
                descend(x, rel, f);
                rel.pop();
            }
        }
        _ => {}
    }
}

/// A predicate on JSON values.
type Matcher = Box<dyn Fn(&Value) -> bool>;

/// A predicate for the values that serde's "invalid type/value/length"
/// message `m` describes (`string "NaN"`, `floating point `1e308``,
/// `integer `-1``, `sequence`, `map`, `null`, `boolean `true``, `invalid
/// length 0`).
fn unexpected_matcher(m: &str) -> Option<Matcher> {
    if let Some(rest) = m.strip_prefix("invalid length ") {
        let n: usize = rest
            .split(|c: char| !c.is_ascii_digit())
            .next()?
            .parse()
            .ok()?;
        return Some(Box::new(move |x| {
            x.as_array().is_some_and(|a| a.len() == n)
        }));
    }
    let rest = m
        .strip_prefix("invalid type: ")
        .or_else(|| m.strip_prefix("invalid value: "))?;
    let what = rest.split(", expected").next()?;
    if let Some(s) = what.strip_prefix("string ") {
        let s: String = serde_json::from_str(s).ok()?;
        return Some(Box::new(move |x| x.as_str() == Some(s.as_str())));
    }
    let number =
        |p: &str| -> Option<f64> { what.strip_prefix(p)?.trim_matches('`').parse::<f64>().ok() };
    if let Some(n) = number("floating point ").or_else(|| number("integer ")) {
        return Some(Box::new(move |x| x.as_f64() == Some(n)));
    }
    if let Some(b) = what.strip_prefix("boolean ") {
        let b = b.trim_matches('`') == "true";
        return Some(Box::new(move |x| x.as_bool() == Some(b)));
    }
    match what {
        "sequence" => Some(Box::new(|x| x.is_array())),
        "map" => Some(Box::new(|x| x.is_object())),
        "null" => Some(Box::new(|x| x.is_null())),
        _ => None,
    }
}

/// The one candidate, or among several the one whose replacement by a
/// harmless value makes the error go away or move (the others leave it).
fn pick<T: DeserializeOwned>(
    doc: &Value,
    steps: &[Step],
    path: &str,
    m: &str,
    candidates: Vec<Vec<Step>>,
) -> Option<Vec<Step>> {
    if candidates.len() <= 1 {
        return candidates.into_iter().next();
    }
    // a bounded number of re-parses (a file with thousands of `[]` is not
    // searched: the ancestor's path stands)
    const MAX_PROBES: usize = 64;
    let neutrals = [
        Value::from(1),
        Value::from(0.5),
        Value::from("x"),
        Value::Array(Vec::new()),
        Value::Bool(false),
    ];
    for rel in candidates.iter().take(MAX_PROBES) {
        let full = [steps, rel.as_slice()].concat();
        for x in &neutrals {
            let mut probe = doc.clone();
            let Some(slot) = lookup_mut(&mut probe, &full) else {
                continue;
            };
            *slot = x.clone();
            let moved = match try_parse::<T>(&probe.to_string()) {
                Ok(_) => true,
                Err((p, m2)) => {
                    // the same failure elsewhere, or one about the neutral itself
                    let about_neutral =
                        unexpected_matcher(&m2).is_some_and(|f| f(x)) && p.starts_with(path);
                    !about_neutral && (p != path || strip_position(&m2) != strip_position(m))
                }
            };
            if moved {
                return Some(rel.clone());
            }
        }
    }
    None
}

/// A message without serde_json's ` at line L column C`.
fn strip_position(m: &str) -> &str {
    m.rsplit_once(" at line ").map_or(m, |(head, _)| head)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
    use super::*;
    use crate::loads::Load;

    #[derive(serde::Deserialize, Debug)]
    #[allow(dead_code)]
    struct Doc {
        loads: Vec<Load>,
    }

    fn path_of(text: &str) -> String {
        parse::<Doc>(text).unwrap_err().path
    }

    /// Inside an internally tagged enum (the loads), the field at fault is
    /// named, not the load: a string, an array, a missing, an unknown field,
    /// an unknown variant.
    #[test]
    fn errors_inside_tagged_enums_name_the_field() {
        for (text, path) in [
            (
                r#"{"loads": [{"type": "tip_force", "force_n": [0, "NaN"]}]}"#,
                "loads[0].force_n[1]",
            ),
            (
                r#"{"loads": [{"type": "tip_force", "force_n": [[], 1]}]}"#,
                "loads[0].force_n[0]",
            ),
            (r#"{"loads": [{"type": "tip_mass"}]}"#, "loads[0].mass_kg"),
            (
                r#"{"loads": [{"type": "tip_mass", "mass_kg": 1, "extra": 2}]}"#,
                "loads[0].extra",
            ),
            (
                r#"{"loads": [{"type": "tip_mas", "mass_kg": 1}]}"#,
                "loads[0].type",
            ),
            (
                r#"{"loads": [{"type": "distributed", "profile": "uniform", "w_n_per_m": [0, []]}]}"#,
                "loads[0].w_n_per_m[1]",
            ),
        ] {
            assert_eq!(path_of(text), path, "{text}");
        }
        // outside a tagged enum the tracked path stands
        assert_eq!(path_of(r#"{"loads": 3}"#), "loads");
        assert_eq!(parse::<Doc>("{").unwrap_err().path, "");
    }
}
