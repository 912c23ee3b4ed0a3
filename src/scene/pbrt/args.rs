//! A directive's arguments: the tokens after its name, read as strings, words, numbers (bare
//! or in brackets), matrices and `"type" params` items, each error placed at its token (in
//! its own file). Owns nothing but reading; the directive's meaning is [`super::parser`]'s.

use super::cursor::Cursor;
use super::lexer::{Token, TokenKind};
use super::params::{ParamError, ParamList, show};
use super::parser::Item;
use super::{PbrtError, Place};
use glam::Mat4;

/// A directive's arguments: the tokens after its name.
pub(super) struct Args<'a> {
    pub tokens: &'a mut Cursor,
    pub place: &'a Place,
    pub directive: &'a str,
}

impl Args<'_> {
    pub(super) fn param_error(&self, e: ParamError) -> PbrtError {
        PbrtError {
            file: e.file,
            line: Some(e.line),
            column: Some(e.column),
            field: format!("{} {}", self.directive, e.field),
            message: e.message,
        }
    }

    fn next(&mut self, what: &str) -> Result<Token, PbrtError> {
        self.tokens.next().ok_or_else(|| {
            self.place
                .error(self.directive, format!("the file ends before its {what}"))
        })
    }

    /// A parameter list, read to the first token that cannot start a parameter.
    pub(super) fn params(&mut self) -> Result<ParamList, PbrtError> {
        ParamList::read(self.tokens).map_err(|e| self.param_error(e))
    }

    fn error_at(&self, t: &Token, message: String) -> PbrtError {
        PbrtError {
            file: t.file.to_path_buf(),
            line: Some(t.line),
            column: Some(t.column),
            field: self.directive.into(),
            message,
        }
    }

    pub(super) fn string(&mut self, what: &str) -> Result<String, PbrtError> {
        let t = self.next(what)?;
        match &t.kind {
            TokenKind::Str(s) => Ok(s.clone()),
            other => Err(self.error_at(
                &t,
                format!(
                    "expected its {what} as a quoted string, found {}",
                    show(other)
                ),
            )),
        }
    }

    pub(super) fn word(&mut self) -> Result<String, PbrtError> {
        let t = self.next("argument")?;
        match &t.kind {
            TokenKind::Word(s) | TokenKind::Str(s) => Ok(s.clone()),
            other => Err(self.error_at(&t, format!("expected a word, found {}", show(other)))),
        }
    }

    fn number(&mut self) -> Result<f32, PbrtError> {
        let t = self.next("numbers")?;
        match &t.kind {
            TokenKind::Number(n) => match n.parse::<f32>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(self.error_at(&t, format!("`{n}` is not a finite number"))),
            },
            other => Err(self.error_at(&t, format!("expected a number, found {}", show(other)))),
        }
    }

    pub(super) fn numbers<const N: usize>(&mut self) -> Result<[f32; N], PbrtError> {
        let bracketed = matches!(
            self.tokens.peek(),
            Some(Token {
                kind: TokenKind::Open,
                ..
            })
        );
        if bracketed {
            self.tokens.next();
        }
        let mut v = [0.0; N];
        for x in &mut v {
            *x = self.number()?;
        }
        if bracketed {
            let t = self.next("closing `]`")?;
            if t.kind != TokenKind::Close {
                return Err(self.error_at(
                    &t,
                    format!("expected `]` after {N} numbers, found {}", show(&t.kind)),
                ));
            }
        }
        Ok(v)
    }

    /// Sixteen numbers, column by column as pbrt writes them (the last four are the translation).
    pub(super) fn matrix(&mut self) -> Result<Mat4, PbrtError> {
        let m = Mat4::from_cols_array(&self.numbers::<16>()?);
        if !m.is_finite() {
            return Err(self.place.error(self.directive, "the matrix is not finite"));
        }
        Ok(m)
    }

    /// `"type"` then a parameter list.
    pub(super) fn item(&mut self) -> Result<Item, PbrtError> {
        let kind = self.string("type")?;
        let params = self.params()?;
        if let Some(t) = self.tokens.peek()
            && matches!(
                t.kind,
                TokenKind::Str(_) | TokenKind::Number(_) | TokenKind::Open
            )
        {
            return Err(self.error_at(
                t,
                format!(
                    "{} is not a parameter (\"type name\") of {} \"{kind}\"",
                    show(&t.kind),
                    self.directive
                ),
            ));
        }
        Ok(Item {
            kind,
            params,
            at: self.place.clone(),
        })
    }
}
