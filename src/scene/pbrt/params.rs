//! pbrt parameter lists: `"type name" value` or `"type name" [values]`, with every type the
//! format has. Owns reading a list and typed access to it; each access marks the parameter as
//! used, so what the mapping never read can be reported as ignored. A parameter given twice
//! keeps its last value, as pbrt-v3's parameter sets do. Must not know what a directive means.

use super::Dialect;
use super::cursor::Cursor;
use super::lexer::{NumberList, Token, TokenKind};
use crate::spectrum;
use glam::Vec3;
use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A parameter's value as written.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Value {
    Number(String),
    /// A long list of numbers, as the lexer kept it ([`NumberList`]).
    Numbers(Arc<NumberList>),
    Str(String),
    Bool(bool),
}

#[derive(Clone, Debug)]
pub(super) struct Param {
    pub ty: String,
    pub name: String,
    pub values: Vec<Value>,
    /// Where the parameter was written: its own file, which after an `Include` need not be
    /// its directive's.
    pub file: Arc<Path>,
    pub line: usize,
    pub column: usize,
    used: Cell<bool>,
}

/// Where in the file a problem is, and what.
#[derive(Debug, PartialEq)]
pub(super) struct ParamError {
    pub file: PathBuf,
    pub line: usize,
    pub column: usize,
    /// `"type name"` as written.
    pub field: String,
    pub message: String,
}

#[derive(Debug, Default)]
pub(super) struct ParamList {
    pub params: Vec<Param>,
    /// One warning per parameter a later one of the same name and kind replaced.
    pub replaced: Vec<String>,
}

const KNOWN_TYPES: &[&str] = &[
    "float",
    "integer",
    "bool",
    "string",
    "point",
    "point2",
    "point3",
    "vector",
    "vector2",
    "vector3",
    "normal",
    "normal3",
    "rgb",
    "color",
    "spectrum",
    "blackbody",
    "texture",
];

impl Param {
    fn error(&self, message: impl Into<String>) -> ParamError {
        ParamError {
            file: self.file.to_path_buf(),
            line: self.line,
            column: self.column,
            field: format!("\"{} {}\"", self.ty, self.name),
            message: message.into(),
        }
    }

    fn numbers(&self) -> Result<Vec<f32>, ParamError> {
        self.values_as("numbers", |text| match text.parse::<f32>() {
            Ok(x) if x.is_finite() => Ok(x),
            Ok(_) => Err(format!("{text} is not a finite number")),
            Err(_) => Err(format!("`{text}` is not a number")),
        })
    }

    fn integers(&self) -> Result<Vec<i64>, ParamError> {
        self.values_as("integers", |text| {
            (text.parse::<i64>()).map_err(|_| format!("`{text}` is not an integer"))
        })
    }

    /// Every value read by `parse` (a long list in parallel), all of them `what`.
    fn values_as<T: Send>(
        &self,
        what: &str,
        parse: impl Fn(&str) -> Result<T, String> + Sync,
    ) -> Result<Vec<T>, ParamError> {
        match &self.values[..] {
            [Value::Numbers(list)] => list.parse(&parse),
            values => (values.iter())
                .map(|v| match v {
                    Value::Number(text) => parse(text),
                    other => Err(format!("expected {what}, found {}", describe(other))),
                })
                .collect(),
        }
        .map_err(|message| self.error(message))
    }
}

fn describe(v: &Value) -> String {
    match v {
        Value::Number(n) => format!("the number {n}"),
        Value::Numbers(list) => format!("a list of {} numbers", list.len()),
        Value::Str(s) => format!("the string \"{s}\""),
        Value::Bool(b) => format!("the word {b}"),
    }
}

impl ParamList {
    /// Reads parameters from `tokens` until the next token that cannot start one.
    pub fn read(tokens: &mut Cursor) -> Result<ParamList, ParamError> {
        let mut list = ParamList::default();
        while let Some(Token {
            kind: TokenKind::Str(decl),
            ..
        }) = tokens.peek()
        {
            let mut words = decl.split_whitespace();
            let (Some(ty), Some(name), None) = (words.next(), words.next(), words.next()) else {
                // A lone string after a directive's own arguments is not a parameter: the
                // caller reports it as a stray token.
                break;
            };
            let (ty, name) = (ty.to_string(), name.to_string());
            let start = tokens.next().expect("peeked");
            let decl = format!("\"{ty} {name}\"");
            let error_at = |t: &Token, message: String| ParamError {
                file: t.file.to_path_buf(),
                line: t.line,
                column: t.column,
                field: decl.clone(),
                message,
            };
            if !KNOWN_TYPES.contains(&ty.as_str()) {
                return Err(error_at(
                    &start,
                    format!("`{ty}` is not a pbrt parameter type"),
                ));
            }
            let mut values = Vec::new();
            match tokens.next() {
                Some(Token {
                    kind: TokenKind::Open,
                    ..
                }) => loop {
                    let Some(t) = tokens.next() else {
                        return Err(error_at(
                            &start,
                            "the value list `[` is never closed".into(),
                        ));
                    };
                    match &t.kind {
                        TokenKind::Close => break,
                        kind => values.push(value(kind).ok_or_else(|| {
                            error_at(&t, format!("unexpected {} in a value list", show(kind)))
                        })?),
                    }
                },
                Some(t) => match value(&t.kind) {
                    Some(v) => values.push(v),
                    None => return Err(error_at(&start, "has no value".into())),
                },
                None => return Err(error_at(&start, "has no value".into())),
            }
            if values.is_empty() {
                return Err(error_at(&start, "has an empty value list".into()));
            }
            let param = Param {
                ty,
                name,
                values,
                file: start.file.clone(),
                line: start.line,
                column: start.column,
                used: Cell::new(false),
            };
            list.add(param);
        }
        Ok(list)
    }

    /// Adds `param`, replacing (with a warning) an earlier one of the same name and kind.
    fn add(&mut self, param: Param) {
        let same = |p: &Param| p.name == param.name && family(&p.ty) == family(&param.ty);
        if let Some(i) = self.params.iter().position(same) {
            let old = self.params.remove(i);
            self.replaced.push(format!(
                "{}:{}:{}: parameter \"{} {}\" is given again at {}:{}:{}; the last value is used",
                old.file.display(),
                old.line,
                old.column,
                old.ty,
                old.name,
                param.file.display(),
                param.line,
                param.column
            ));
        }
        self.params.push(param);
    }

    /// Adds each of `defaults` whose name this list does not give (pbrt-v4's `Attribute`).
    pub fn add_defaults(&mut self, defaults: &[Param]) {
        for d in defaults {
            if !self.params.iter().any(|p| p.name == d.name) {
                self.params.push(d.clone());
            }
        }
    }

    /// Parameter `name`: a texture first, as pbrt looks textures up first, else the last one.
    fn lookup(&self, name: &str) -> Option<&Param> {
        let named = || self.params.iter().filter(|p| p.name == name);
        named()
            .find(|p| p.ty == "texture")
            .or_else(|| named().last())
    }

    /// [`Self::lookup`], marking the parameter as read.
    fn find(&self, name: &str) -> Option<&Param> {
        let p = self.lookup(name)?;
        p.used.set(true);
        Some(p)
    }

    /// Checks `p`'s declared type is one of `types`; a texture gets its own message.
    fn typed<'a>(&self, p: &'a Param, types: &[&str]) -> Result<&'a Param, ParamError> {
        if types.contains(&p.ty.as_str()) {
            return Ok(p);
        }
        if p.ty == "texture" {
            return Err(p.error("textures are not supported: give a constant value"));
        }
        Err(p.error(format!("must be of type {}", types.join(" or "))))
    }

    /// The texture parameter `name` names, when `name` is given as a `texture` (pbrt looks
    /// textures up first); `None` when it is absent or a constant.
    pub fn texture(&self, name: &str) -> Result<Option<String>, ParamError> {
        let Some(p) = self.lookup(name).filter(|p| p.ty == "texture") else {
            return Ok(None);
        };
        p.used.set(true);
        match &p.values[..] {
            [Value::Str(s)] => Ok(Some(s.clone())),
            _ => Err(p.error("must be one texture name (a string)")),
        }
    }

    pub fn floats(&self, name: &str) -> Result<Option<Vec<f32>>, ParamError> {
        self.find(name)
            .map(|p| self.typed(p, &["float"])?.numbers())
            .transpose()
    }

    pub fn float(&self, name: &str) -> Result<Option<f32>, ParamError> {
        self.one(name, &["float"], |p| Ok(p.numbers()?[0]))
    }

    pub fn integers(&self, name: &str) -> Result<Option<Vec<i64>>, ParamError> {
        self.find(name)
            .map(|p| self.typed(p, &["integer"])?.integers())
            .transpose()
    }

    pub fn integer(&self, name: &str) -> Result<Option<i64>, ParamError> {
        self.one(name, &["integer"], |p| Ok(p.integers()?[0]))
    }

    pub fn string(&self, name: &str) -> Result<Option<String>, ParamError> {
        self.one(name, &["string"], |p| match &p.values[0] {
            Value::Str(s) => Ok(s.clone()),
            other => Err(p.error(format!("expected a string, found {}", describe(other)))),
        })
    }

    /// Every value of a `string` parameter (pbrt-v4's `"string materials" ["a" "b"]`).
    pub fn strings(&self, name: &str) -> Result<Option<Vec<String>>, ParamError> {
        let Some(p) = self.find(name) else {
            return Ok(None);
        };
        let p = self.typed(p, &["string"])?;
        (p.values.iter())
            .map(|v| match v {
                Value::Str(s) => Ok(s.clone()),
                other => Err(p.error(format!("expected strings, found {}", describe(other)))),
            })
            .collect::<Result<_, _>>()
            .map(Some)
    }

    pub fn bool(&self, name: &str) -> Result<Option<bool>, ParamError> {
        self.one(name, &["bool"], |p| match &p.values[0] {
            Value::Bool(b) => Ok(*b),
            Value::Str(s) if s == "true" => Ok(true),
            Value::Str(s) if s == "false" => Ok(false),
            other => Err(p.error(format!("expected true or false, found {}", describe(other)))),
        })
    }

    /// Triples of a point, vector or normal type.
    pub fn vec3s(&self, name: &str) -> Result<Option<Vec<Vec3>>, ParamError> {
        let types = [
            "point", "point3", "vector", "vector3", "normal", "normal3", "float",
        ];
        self.find(name)
            .map(|p| {
                let xs = self.typed(p, &types)?.numbers()?;
                if xs.len() % 3 != 0 {
                    return Err(p.error(format!("has {} numbers, not a multiple of 3", xs.len())));
                }
                Ok(xs
                    .chunks_exact(3)
                    .map(|c| Vec3::new(c[0], c[1], c[2]))
                    .collect())
            })
            .transpose()
    }

    /// Pairs of a `point2` or `vector2`, or `float`s taken two at a time (pbrt-v3's `uv`).
    pub fn vec2s(&self, name: &str) -> Result<Option<Vec<glam::Vec2>>, ParamError> {
        self.find(name)
            .map(|p| {
                let xs = self.typed(p, &["point2", "vector2", "float"])?.numbers()?;
                if xs.len() % 2 != 0 {
                    return Err(p.error(format!("has {} numbers, not a multiple of 2", xs.len())));
                }
                Ok(xs
                    .chunks_exact(2)
                    .map(|c| glam::Vec2::new(c[0], c[1]))
                    .collect())
            })
            .transpose()
    }

    pub fn vec3(&self, name: &str) -> Result<Option<Vec3>, ParamError> {
        match self.vec3s(name)? {
            None => Ok(None),
            Some(v) if v.len() == 1 => Ok(Some(v[0])),
            Some(_) => Err(self.single_value_error(name, "3 numbers")),
        }
    }

    /// A constant colour: `rgb`/`color` triples, a `spectrum` given as one constant (a
    /// single number, or (λ, value) pairs that all have the same value), or a `float`.
    /// Spectra by name or that vary with λ, blackbodies and textures are refused.
    pub fn colour(&self, name: &str) -> Result<Option<Vec3>, ParamError> {
        let types = ["rgb", "color", "spectrum", "float", "blackbody"];
        let Some(p) = self.find(name) else {
            return Ok(None);
        };
        let p = self.typed(p, &types)?;
        match p.ty.as_str() {
            "rgb" | "color" => {
                let xs = p.numbers()?;
                match xs[..] {
                    [r, g, b] => Ok(Some(Vec3::new(r, g, b))),
                    _ => Err(p.error(format!("has {} numbers; an RGB has 3", xs.len()))),
                }
            }
            "float" => match p.numbers()?[..] {
                [x] => Ok(Some(Vec3::splat(x))),
                ref xs => Err(p.error(format!("has {} numbers; expected 1", xs.len()))),
            },
            "spectrum" => {
                if let Value::Str(s) = &p.values[0] {
                    return Err(p.error(format!(
                        "the named or file spectrum \"{s}\" is not supported: give a constant"
                    )));
                }
                let xs = p.numbers()?;
                match xs[..] {
                    [x] => Ok(Some(Vec3::splat(x))),
                    _ if xs.len() % 2 == 0 => {
                        let v = xs[1];
                        if xs.chunks_exact(2).all(|pair| pair[1] == v) {
                            Ok(Some(Vec3::splat(v)))
                        } else {
                            Err(p.error("a spectrum that varies with wavelength is not supported: give an rgb value"))
                        }
                    }
                    _ => Err(p.error("a spectrum is one constant or (wavelength, value) pairs")),
                }
            }
            _ => Err(p.error(
                "a blackbody is read only where a light's emission is: give an rgb value here",
            )),
        }
    }

    /// A light's emission: [`Self::colour`], or a `blackbody` through Planck's law and the CIE
    /// 1931 observer to linear sRGB. pbrt-v3 writes `[T scale]` and normalises the spectrum to
    /// 1 at its peak; pbrt-v4 writes `T`, and its lights divide the spectrum by its
    /// luminance, so a pbrt-v4 blackbody has luminance 1 (an `rgb` keeps its magnitude).
    pub fn emission(&self, name: &str, dialect: Dialect) -> Result<Option<Vec3>, ParamError> {
        match self.lookup(name) {
            Some(p) if p.ty == "blackbody" => {
                p.used.set(true);
                let xs = p.numbers()?;
                let (kelvin, scale) = match (dialect, &xs[..]) {
                    (Dialect::V3, [t]) => (*t, 1.0),
                    (Dialect::V3, [t, s]) => (*t, *s),
                    (Dialect::V3, _) => {
                        return Err(p.error(format!(
                            "has {} numbers; a light's pbrt-v3 blackbody is [temperature scale]",
                            xs.len()
                        )));
                    }
                    (Dialect::V4, [t]) => (*t, 1.0),
                    (Dialect::V4, _) => {
                        return Err(p.error(format!(
                            "has {} numbers; a pbrt-v4 blackbody is one temperature",
                            xs.len()
                        )));
                    }
                };
                if kelvin <= 0.0 {
                    return Err(p.error(format!("{kelvin} K is not a positive temperature")));
                }
                let xyz = spectrum::blackbody_xyz(kelvin as f64);
                let xyz = match dialect {
                    Dialect::V3 => xyz,
                    Dialect::V4 => xyz / xyz.y,
                };
                Ok(Some(spectrum::xyz_to_linear_srgb(xyz).as_vec3() * scale))
            }
            _ => self.colour(name),
        }
    }

    /// The named spectrum a `spectrum` parameter gives as a string, if it is one.
    pub fn spectrum_name(&self, name: &str) -> Option<String> {
        let p = self.lookup(name)?;
        match (&p.ty[..], &p.values[..]) {
            ("spectrum", [Value::Str(s)]) => {
                p.used.set(true);
                Some(s.clone())
            }
            _ => None,
        }
    }

    /// Marks `name` as read on purpose without using its value.
    pub fn mark_used(&self, name: &str) {
        if let Some(p) = self.lookup(name) {
            p.used.set(true);
        }
    }

    /// The parameters in this list that no accessor read, for warnings.
    pub fn unused(&self) -> Vec<String> {
        self.params
            .iter()
            .filter(|p| !p.used.get())
            .map(|p| format!("\"{} {}\"", p.ty, p.name))
            .collect()
    }

    /// Location of parameter `name`, or `None`.
    pub fn at(&self, name: &str) -> Option<(usize, usize)> {
        let p = self.lookup(name)?;
        Some((p.line, p.column))
    }

    /// An error placed at parameter `name`.
    pub fn error_at(&self, name: &str, message: impl Into<String>) -> Option<ParamError> {
        let p = self.lookup(name)?;
        Some(p.error(message))
    }

    fn single_value_error(&self, name: &str, what: &str) -> ParamError {
        self.error_at(name, format!("must be exactly {what}"))
            .expect("called for a parameter that exists")
    }

    fn one<T>(
        &self,
        name: &str,
        types: &[&str],
        read: impl FnOnce(&Param) -> Result<T, ParamError>,
    ) -> Result<Option<T>, ParamError> {
        let Some(p) = self.find(name) else {
            return Ok(None);
        };
        let p = self.typed(p, types)?;
        let count = match &p.values[..] {
            [Value::Numbers(list)] => list.len(),
            values => values.len(),
        };
        if count != 1 {
            return Err(p.error(format!("has {count} values; expected one")));
        }
        read(p).map(Some)
    }
}

/// The kind a parameter type belongs to: pbrt keeps one value of each name and kind (its
/// spectra are `rgb`, `color`, `spectrum` and `blackbody` alike).
fn family(ty: &str) -> &str {
    match ty {
        "point" | "point3" => "point3",
        "vector" | "vector3" => "vector3",
        "normal" | "normal3" => "normal3",
        "rgb" | "color" | "spectrum" | "blackbody" => "spectrum",
        other => other,
    }
}

fn value(kind: &TokenKind) -> Option<Value> {
    match kind {
        TokenKind::Number(n) => Some(Value::Number(n.clone())),
        TokenKind::Numbers(list) => Some(Value::Numbers(list.clone())),
        TokenKind::Str(s) => Some(Value::Str(s.clone())),
        TokenKind::Word(w) if w == "true" => Some(Value::Bool(true)),
        TokenKind::Word(w) if w == "false" => Some(Value::Bool(false)),
        _ => None,
    }
}

pub(super) fn show(kind: &TokenKind) -> String {
    match kind {
        TokenKind::Str(s) => format!("string \"{s}\""),
        TokenKind::Number(n) => format!("number {n}"),
        TokenKind::Numbers(list) => format!("list of {} numbers", list.len()),
        TokenKind::Word(w) => format!("`{w}`"),
        TokenKind::Open => "`[`".into(),
        TokenKind::Close => "`]`".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::super::lexer::test_tokens;
    use super::*;

    fn list(text: &str) -> Result<ParamList, ParamError> {
        let mut cursor = Cursor::new(test_tokens(text).unwrap(), "test.pbrt".into());
        let list = ParamList::read(&mut cursor)?;
        assert!(cursor.peek().is_none(), "every token read");
        Ok(list)
    }

    #[test]
    fn reads_every_value_form() {
        let l = list(
            r#""float radius" 2 "rgb Kd" [0.1 0.2 0.3] "bool twosided" true
               "string filename" ["a.ply"] "point3 P" [0 0 0 1 0 0 0 1 0]
               "integer indices" [0 1 2] "spectrum Kr" [300 0.5 800 0.5]"#,
        )
        .unwrap();
        assert_eq!(l.float("radius").unwrap(), Some(2.0));
        assert_eq!(l.colour("Kd").unwrap(), Some(Vec3::new(0.1, 0.2, 0.3)));
        assert_eq!(l.bool("twosided").unwrap(), Some(true));
        assert_eq!(l.string("filename").unwrap().as_deref(), Some("a.ply"));
        assert_eq!(l.vec3s("P").unwrap().unwrap().len(), 3);
        assert_eq!(l.integers("indices").unwrap(), Some(vec![0, 1, 2]));
        assert_eq!(l.colour("Kr").unwrap(), Some(Vec3::splat(0.5)));
        assert!(l.unused().is_empty());
        assert_eq!(l.float("absent").unwrap(), None);
    }

    #[test]
    fn refuses_what_it_cannot_represent_at_the_parameter() {
        let l = list(r#""texture Kd" "checks" "blackbody I" [5500] "spectrum eta" "metal-Cu-eta""#)
            .unwrap();
        let e = l.colour("Kd").unwrap_err();
        assert!(e.message.contains("textures"), "{e:?}");
        assert_eq!((e.line, e.column), (1, 1));
        assert!(l.colour("I").unwrap_err().message.contains("blackbody"));
        assert!(l.colour("eta").unwrap_err().message.contains("named"));
        assert_eq!(l.spectrum_name("eta").as_deref(), Some("metal-Cu-eta"));
    }

    #[test]
    fn a_long_list_reads_and_fails_as_a_short_one_does() {
        let numbers: Vec<String> = (0..2000).map(|i| format!("{i}")).collect();
        let long = numbers.join(" ");
        let l = list(&format!(
            "\"integer indices\" [{long}]\n\"point3 P\" [{long} 0]\n\"float radius\" [{long}]\n\
             \"integer bad\" [{long} 1.5]\n\"string s\" [{long}]"
        ))
        .unwrap();
        let indices = l.integers("indices").unwrap().unwrap();
        assert_eq!(indices, (0..2000).collect::<Vec<i64>>());
        let p = l.vec3s("P").unwrap().unwrap();
        assert_eq!((p.len(), p[666]), (667, Vec3::new(1998.0, 1999.0, 0.0)));
        let e = l.float("radius").unwrap_err();
        assert!(e.message.contains("has 2000 values; expected one"), "{e:?}");
        let e = l.integers("bad").unwrap_err();
        assert!(e.message.contains("`1.5` is not an integer"), "{e:?}");
        assert_eq!(
            (e.line, e.column, e.field.as_str()),
            (4, 1, "\"integer bad\"")
        );
        let e = l.strings("s").unwrap_err();
        assert!(e.message.contains("found a list of 2000 numbers"), "{e:?}");
    }

    #[test]
    fn malformed_lists_are_errors_with_places() {
        for (text, needle) in [
            (r#""float radius" [1"#, "never closed"),
            (r#""float radius""#, "no value"),
            (r#""float radius" []"#, "empty"),
            (r#""float3 radius" 1"#, "not a pbrt parameter type"),
            (r#""float r" [1 Shape]"#, "unexpected"),
        ] {
            let e = list(text).unwrap_err();
            assert!(e.message.contains(needle), "{text}: {e:?}");
        }
        let l = list(r#""float r" [-inf] "integer n" 2.5 "rgb c" [1 2]"#).unwrap();
        assert!(l.float("r").unwrap_err().message.contains("finite"));
        assert!(l.integer("n").unwrap_err().message.contains("integer"));
        assert!(l.colour("c").unwrap_err().message.contains("3"));
    }
}
