//! `--set key=value`: a case file changed from the command line, as the verification suite
//! does to run one model at several resolutions or end times without a copy per variant.

use super::CaseError;
use toml::{Table, Value};

/// Apply one `key=value` to the parsed file (see [`super::Case::load_with`]).
pub(super) fn apply(table: &mut Table, set: &str) -> Result<(), CaseError> {
    let err = |m: String| CaseError(format!("--set {set:?}: {m}"));
    let (key, value) = set
        .split_once('=')
        .ok_or_else(|| err("expected key=value, e.g. time.t_end=0.1".into()))?;
    let (key, value) = (key.trim(), value.trim());
    // a value is what TOML would read on the right of `x = `
    let value: Value = toml::from_str::<Table>(&format!("x = {value}"))
        .map_err(|_| {
            err(format!(
                "{value:?} is not a TOML value (numbers as 0.1, strings in quotes, arrays as [1, 2])"
            ))
        })?
        .remove("x")
        .ok_or_else(|| err("no value".into()))?;
    let path: Vec<&str> = key.split('.').collect();
    if path.iter().any(|p| p.is_empty()) {
        return Err(err(format!("{key:?} has an empty segment")));
    }
    let n = set_in_table(table, &path, &value, key).map_err(err)?;
    if n == 0 {
        return Err(err(format!(
            "{key:?}: the array of tables it names is empty"
        )));
    }
    Ok(())
}

/// Set `path` below `table`; returns how many entries were set (several for `*`).
fn set_in_table(
    table: &mut Table,
    path: &[&str],
    value: &Value,
    key: &str,
) -> Result<usize, String> {
    let (head, rest) = (path[0], &path[1..]);
    if rest.is_empty() {
        table.insert(head.to_string(), value.clone());
        return Ok(1);
    }
    let known = table.keys().cloned().collect::<Vec<_>>().join(", ");
    let child = table
        .get_mut(head)
        .ok_or_else(|| format!("{key:?}: no table {head:?} in the case (it has {known})"))?;
    set_in_value(child, rest, value, key)
}

fn set_in_value(v: &mut Value, path: &[&str], value: &Value, key: &str) -> Result<usize, String> {
    match v {
        Value::Table(t) => set_in_table(t, path, value, key),
        Value::Array(a) => {
            let (head, rest) = (path[0], &path[1..]);
            let indices: Vec<usize> = if head == "*" {
                (0..a.len()).collect()
            } else {
                let i: usize = head.parse().map_err(|_| {
                    format!("{key:?}: {head:?} must be an index 0..{} or *", a.len())
                })?;
                if i >= a.len() {
                    return Err(format!("{key:?}: index {i} out of range 0..{}", a.len()));
                }
                vec![i]
            };
            let mut n = 0;
            for i in indices {
                n += if rest.is_empty() {
                    a[i] = value.clone();
                    1
                } else {
                    set_in_value(&mut a[i], rest, value, key)?
                };
            }
            Ok(n)
        }
        _ => Err(format!("{key:?}: {:?} is a value, not a table", path[0])),
    }
}
