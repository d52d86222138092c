//! Typed reads from a TOML table, each failure one line naming the file, the key path and what is allowed.

use toml::{Table, Value};

use crate::error::Error;

/// A TOML table and where it sits (file, key path) for error messages.
pub struct Section<'a> {
    file: &'a str,
    path: String,
    table: &'a Table,
}

impl<'a> Section<'a> {
    /// The file's top-level table.
    pub fn root(file: &'a str, table: &'a Table) -> Self {
        Self { file, path: String::new(), table }
    }

    /// The key path of `key` in this section (e.g. `sweep.objects`).
    pub fn key_path(&self, key: &str) -> String {
        if self.path.is_empty() { key.to_string() } else { format!("{}.{key}", self.path) }
    }

    /// A bad-input error about `key`.
    pub fn error(&self, key: &str, message: impl std::fmt::Display) -> Error {
        Error::Input(format!("{}: {}: {message}", self.file, self.key_path(key)))
    }

    /// A bad-input error about the section as a whole.
    pub fn error_here(&self, message: impl std::fmt::Display) -> Error {
        let at = if self.path.is_empty() { String::new() } else { format!("{}: ", self.path) };
        Error::Input(format!("{}: {at}{message}", self.file))
    }

    /// Rejects every key not in `allowed`.
    pub fn only(&self, allowed: &[&str]) -> Result<(), Error> {
        match self.table.keys().find(|k| !allowed.contains(&k.as_str())) {
            Some(k) => Err(self.error(k, format!("unknown key (allowed: {})", allowed.join(", ")))),
            None => Ok(()),
        }
    }

    /// The keys present, in file order.
    pub fn keys(&self) -> impl Iterator<Item = &'a String> {
        self.table.keys()
    }

    /// The raw value of `key`.
    pub fn get(&self, key: &str) -> Option<&'a Value> {
        self.table.get(key)
    }

    fn typed<T>(&self, key: &str, want: &str, f: impl Fn(&'a Value) -> Option<T>) -> Result<Option<T>, Error> {
        match self.table.get(key) {
            None => Ok(None),
            Some(v) => {
                f(v).map(Some).ok_or_else(|| self.error(key, format!("expected {want}, found a {}", v.type_str())))
            }
        }
    }

    /// An optional string.
    pub fn string(&self, key: &str) -> Result<Option<&'a str>, Error> {
        self.typed(key, "a string", Value::as_str)
    }

    /// A required string.
    pub fn required_string(&self, key: &str) -> Result<&'a str, Error> {
        self.string(key)?.ok_or_else(|| self.error_here(format!("missing key {:?} (a string)", key)))
    }

    /// An optional boolean.
    pub fn boolean(&self, key: &str) -> Result<Option<bool>, Error> {
        self.typed(key, "true or false", Value::as_bool)
    }

    /// An optional integer in `lo..=hi`.
    pub fn integer(&self, key: &str, lo: i64, hi: i64) -> Result<Option<i64>, Error> {
        match self.typed(key, &format!("an integer in {lo}..={hi}"), Value::as_integer)? {
            Some(v) if !(lo..=hi).contains(&v) => {
                Err(self.error(key, format!("{v} is out of range (allowed: {lo}..={hi})")))
            }
            v => Ok(v),
        }
    }

    /// An optional number (integer or float) in `lo..=hi`.
    pub fn number(&self, key: &str, lo: f64, hi: f64) -> Result<Option<f64>, Error> {
        let as_f64 = |v: &Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
        match self.typed(key, &format!("a number in {lo}..={hi}"), as_f64)? {
            Some(v) if !(lo..=hi).contains(&v) => {
                Err(self.error(key, format!("{v} is out of range (allowed: {lo}..={hi})")))
            }
            v => Ok(v),
        }
    }

    /// A string or a list of strings, as a list (absent: `None`).
    pub fn strings(&self, key: &str) -> Result<Option<Vec<String>>, Error> {
        let Some(v) = self.table.get(key) else { return Ok(None) };
        let items: Vec<&Value> = match v {
            Value::Array(a) => a.iter().collect(),
            one => vec![one],
        };
        items
            .into_iter()
            .map(|i| {
                i.as_str()
                    .map(str::to_string)
                    .ok_or_else(|| self.error(key, format!("expected strings, found a {}", i.type_str())))
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    }

    /// An optional sub-table.
    pub fn section(&self, key: &str) -> Result<Option<Section<'a>>, Error> {
        let t = self.typed(key, "a table", Value::as_table)?;
        Ok(t.map(|table| Section { file: self.file, path: self.key_path(key), table }))
    }

    /// An optional array of tables (`[[key]]`), each with its index in the path.
    pub fn sections(&self, key: &str) -> Result<Vec<Section<'a>>, Error> {
        let Some(v) = self.table.get(key) else { return Ok(vec![]) };
        let arr = v
            .as_array()
            .ok_or_else(|| self.error(key, format!("expected [[{key}]] tables, found a {}", v.type_str())))?;
        arr.iter()
            .enumerate()
            .map(|(i, item)| {
                let path = format!("{}[{i}]", self.key_path(key));
                let table = item.as_table().ok_or_else(|| {
                    Error::Input(format!("{}: {path}: expected a table, found a {}", self.file, item.type_str()))
                })?;
                Ok(Section { file: self.file, path, table })
            })
            .collect()
    }
}
