//! A PLY body as the header describes it: one element instance per line in an ASCII file,
//! packed scalars of either byte order in a binary one. Owns reading values and where an
//! error is (line or element); [`super`] decides what the values mean.

use super::{Element, PlyError, Property, Scalar, header_error};

pub(super) fn element_error(
    reader: &Body,
    element: &str,
    i: usize,
    message: impl Into<String>,
) -> PlyError {
    PlyError {
        line: reader.line(),
        field: format!("{element}[{i}]"),
        message: message.into(),
    }
}

pub(super) enum Body<'a> {
    Ascii(AsciiBody<'a>),
    Binary {
        bytes: &'a [u8],
        at: usize,
        big: bool,
    },
}

/// An ASCII body: one element instance per line.
pub(super) struct AsciiBody<'a> {
    lines: Vec<&'a str>,
    first_line: usize,
    /// Index of the current line in `lines`, and of the next word in it.
    line: usize,
    words: Vec<&'a str>,
    word: usize,
}

impl<'a> AsciiBody<'a> {
    pub(super) fn new(body: &'a [u8], header_lines: usize) -> Result<Self, PlyError> {
        let text = std::str::from_utf8(body).map_err(|e| PlyError {
            line: Some(
                header_lines
                    + 1
                    + body[..e.valid_up_to()]
                        .iter()
                        .filter(|&&b| b == b'\n')
                        .count(),
            ),
            field: "body".into(),
            message: "an ASCII PLY body is not text".into(),
        })?;
        Ok(AsciiBody {
            lines: text.lines().collect(),
            first_line: header_lines + 1,
            line: 0,
            words: Vec::new(),
            word: 0,
        })
    }
}

impl Body<'_> {
    pub(super) fn line(&self) -> Option<usize> {
        match self {
            Body::Ascii(a) => Some(a.first_line + a.line.saturating_sub(1)),
            Body::Binary { .. } => None,
        }
    }

    /// Refuses counts the file cannot hold, before anything is allocated for them.
    pub(super) fn check_counts(&self, elements: &[Element]) -> Result<(), PlyError> {
        let available = match self {
            Body::Ascii(a) => a.lines.iter().filter(|l| !l.trim().is_empty()).count(),
            Body::Binary { bytes, .. } => bytes.len(),
        };
        let mut needed: usize = 0;
        for e in elements {
            let per = match self {
                Body::Ascii(_) => 1,
                Body::Binary { .. } => e
                    .properties
                    .iter()
                    .map(Property::min_size)
                    .sum::<usize>()
                    .max(1),
            };
            needed = needed.saturating_add(e.count.saturating_mul(per));
            if needed > available {
                let unit = if matches!(self, Body::Ascii(_)) {
                    "lines"
                } else {
                    "bytes"
                };
                return Err(header_error(
                    e.line,
                    &format!("element {}", e.name),
                    format!(
                        "claims {} elements, but the file has only {available} {unit} of body for every element up to this one (truncated or a wrong count)",
                        e.count
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The binary body from the reader's place on, and whether it is big-endian; `None` for
    /// an ASCII body.
    pub(super) fn binary_rest(&self) -> Option<(&[u8], bool)> {
        match self {
            Body::Binary { bytes, at, big } => Some((&bytes[*at..], *big)),
            Body::Ascii(_) => None,
        }
    }

    /// The next `count` lines of an ASCII body, when there are that many and none is blank
    /// (a line an element); `None` for a binary body.
    pub(super) fn ascii_lines(&self, count: usize) -> Option<&[&str]> {
        let Body::Ascii(a) = self else { return None };
        let lines = a.lines.get(a.line..a.line.checked_add(count)?)?;
        use rayon::prelude::*;
        (!lines.par_iter().any(|l| l.trim().is_empty())).then_some(lines)
    }

    /// Moves an ASCII reader `count` lines on (what [`Body::ascii_lines`] handed out was read).
    pub(super) fn skip_lines(&mut self, count: usize) {
        if let Body::Ascii(a) = self {
            a.line += count;
        }
    }

    /// Moves a binary reader `n` bytes on (what [`Body::binary_rest`] handed out was read).
    pub(super) fn advance(&mut self, n: usize) {
        if let Body::Binary { at, .. } = self {
            *at += n;
        }
    }

    pub(super) fn begin(&mut self, element: &str, i: usize) -> Result<(), PlyError> {
        if let Body::Ascii(a) = self {
            loop {
                let Some(text) = a.lines.get(a.line) else {
                    return Err(PlyError {
                        line: Some(a.first_line + a.line),
                        field: format!("{element}[{i}]"),
                        message: "the file ends before this element".into(),
                    });
                };
                a.line += 1;
                a.words = text.split_whitespace().collect();
                a.word = 0;
                if !a.words.is_empty() {
                    return Ok(());
                }
            }
        }
        Ok(())
    }

    pub(super) fn end(&mut self, element: &str, i: usize) -> Result<(), PlyError> {
        if let Body::Ascii(a) = self
            && a.word != a.words.len()
        {
            return Err(PlyError {
                line: Some(a.first_line + a.line - 1),
                field: format!("{element}[{i}]"),
                message: format!(
                    "has {} values; its properties take {}",
                    a.words.len(),
                    a.word
                ),
            });
        }
        Ok(())
    }

    pub(super) fn scalar(&mut self, ty: Scalar, element: &str, i: usize) -> Result<f64, PlyError> {
        let field = || format!("{element}[{i}]");
        match self {
            Body::Ascii(a) => {
                let line = Some(a.first_line + a.line - 1);
                let Some(word) = a.words.get(a.word) else {
                    return Err(PlyError {
                        line,
                        field: field(),
                        message: "has too few values for its properties".into(),
                    });
                };
                a.word += 1;
                let bad = || PlyError {
                    line,
                    field: field(),
                    message: format!("`{word}` is not a {ty:?} value"),
                };
                if ty.is_integer() {
                    word.parse::<i64>().map(|v| v as f64).map_err(|_| bad())
                } else {
                    word.parse::<f64>().map_err(|_| bad())
                }
            }
            Body::Binary { bytes, at, big } => {
                let size = ty.size();
                let Some(raw) = bytes.get(*at..*at + size) else {
                    return Err(PlyError {
                        line: None,
                        field: field(),
                        message: format!("the file ends inside this element (byte {})", *at),
                    });
                };
                *at += size;
                Ok(ty.decode(raw, *big))
            }
        }
    }

    pub(super) fn skip(&mut self, p: &Property, element: &str, i: usize) -> Result<(), PlyError> {
        match p {
            Property::Scalar { ty, .. } => self.scalar(*ty, element, i).map(drop),
            Property::List { count, item, .. } => {
                let n = self.scalar(*count, element, i)?;
                if n < 0.0 {
                    return Err(PlyError {
                        line: self.line(),
                        field: format!("{element}[{i}]"),
                        message: format!("a list has a negative length {n}"),
                    });
                }
                for _ in 0..n as usize {
                    self.scalar(*item, element, i)?;
                }
                Ok(())
            }
        }
    }
}
