//! The token stream the parser reads, as pbrt reads it: `Include` puts the included file's
//! tokens in front of the rest of the stream, so a parameter list may run on from the end of an
//! included file into the file that included it. A stack of files' tokens, each token still
//! naming its own file. Owns the order tokens are read in; must not know directives.

use super::lexer::Token;
use std::path::PathBuf;

/// One file's tokens still to read, last first (reading pops).
struct Stream {
    rest: Vec<Token>,
    identity: PathBuf,
}

#[derive(Default)]
pub(super) struct Cursor {
    streams: Vec<Stream>,
}

impl Cursor {
    /// A cursor over one file's tokens; `identity` names the file for cycle checks.
    pub fn new(tokens: Vec<Token>, identity: PathBuf) -> Self {
        let mut cursor = Cursor::default();
        cursor.push(tokens, identity);
        cursor
    }

    /// Puts `tokens` in front of everything not yet read.
    pub fn push(&mut self, mut tokens: Vec<Token>, identity: PathBuf) {
        tokens.reverse();
        self.streams.push(Stream {
            rest: tokens,
            identity,
        });
    }

    /// The next token, without reading it.
    pub fn peek(&self) -> Option<&Token> {
        self.streams.iter().rev().find_map(|s| s.rest.last())
    }

    /// Reads the next token. A file read to its end is left on the stack until the token after
    /// it is read, so an `Include` that ends a file still counts that file as open.
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> Option<Token> {
        while self.streams.len() > 1 && self.streams.last().is_some_and(|s| s.rest.is_empty()) {
            self.streams.pop();
        }
        self.streams.last_mut()?.rest.pop()
    }

    /// Whether the file `identity` is open (being read, or included by one being read).
    pub fn is_open(&self, identity: &PathBuf) -> bool {
        self.streams.iter().any(|s| &s.identity == identity)
    }

    /// The files open, outermost first.
    pub fn open_files(&self) -> impl Iterator<Item = &PathBuf> {
        self.streams.iter().map(|s| &s.identity)
    }

    /// How many files are open.
    pub fn depth(&self) -> usize {
        self.streams.len()
    }
}

#[cfg(test)]
mod tests {
    use super::super::lexer::{TokenKind, test_tokens};
    use super::*;

    fn words(cursor: &mut Cursor) -> Vec<String> {
        std::iter::from_fn(|| cursor.next())
            .map(|t| match t.kind {
                TokenKind::Word(w) | TokenKind::Number(w) | TokenKind::Str(w) => w,
                other => format!("{other:?}"),
            })
            .collect()
    }

    #[test]
    fn pushed_tokens_come_before_the_rest_and_the_outer_file_resumes() {
        let mut cursor = Cursor::new(test_tokens("a b c").unwrap(), "outer".into());
        assert_eq!(cursor.next().unwrap().kind, TokenKind::Word("a".into()));
        cursor.push(test_tokens("x y").unwrap(), "inner".into());
        assert!(cursor.is_open(&"outer".into()) && cursor.is_open(&"inner".into()));
        assert_eq!(cursor.depth(), 2);
        assert_eq!(words(&mut cursor), ["x", "y", "b", "c"]);
    }

    #[test]
    fn a_file_read_to_its_end_stays_open_until_the_next_read() {
        let mut cursor = Cursor::new(test_tokens("a").unwrap(), "outer".into());
        cursor.next();
        cursor.push(test_tokens("").unwrap(), "inner".into());
        assert_eq!(cursor.depth(), 2);
        assert!(cursor.peek().is_none());
        assert!(cursor.next().is_none());
        assert_eq!(cursor.open_files().count(), 1);
    }
}
