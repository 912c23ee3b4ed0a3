//! pbrt's tokens: quoted strings, numbers, `[` `]`, bare words (directives and `true`/`false`),
//! with `#` comments skipped. A long bracketed list of nothing but numbers (a big
//! `trianglemesh`'s indices or points) is one token holding its text, parsed later in
//! parallel, not a token a number. Every token carries its file and its 1-based line and column (in
//! characters) so the parser's errors can name them wherever `Include` splices it. Owns
//! nothing but the text of one file; must not know directives or parameter types.

use std::path::Path;
use std::sync::Arc;

/// What a token is.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum TokenKind {
    /// A quoted string, quotes removed and escapes (`\"`, `\\`, `\n`, `\t`) decoded.
    Str(String),
    /// A number as written (parsed by whoever knows whether it must be an integer).
    Number(String),
    /// A bare word: a directive name, `true`/`false`, or something malformed.
    Word(String),
    Open,
    Close,
    /// The text between `[` and `]` when it is at least [`NUMBER_LIST_MIN_BYTES`] of number
    /// characters and whitespace only (the brackets stay tokens of their own).
    Numbers(Arc<NumberList>),
}

/// Shorter lists of numbers are lexed a token a number (cheap, and their errors point at the
/// number); longer ones are kept as text.
pub(super) const NUMBER_LIST_MIN_BYTES: usize = 4096;

/// A long list of numbers as written: whitespace-separated words of `0-9 + - . e E`.
#[derive(Debug, PartialEq)]
pub(super) struct NumberList {
    pub text: String,
}

impl NumberList {
    /// The list's words, parsed in parallel (in pieces split at whitespace); the first word
    /// `parse` refuses, with its error, otherwise.
    pub(super) fn parse<T: Send, E: Send>(
        &self,
        parse: impl Fn(&str) -> Result<T, E> + Sync,
    ) -> Result<Vec<T>, E> {
        use rayon::prelude::*;
        const PIECE: usize = 1 << 16;
        let bytes = self.text.as_bytes();
        let mut cuts = vec![0];
        while let Some(&last) = cuts.last()
            && last + PIECE < bytes.len()
        {
            let past = (bytes[last + PIECE..].iter()).position(|b| b.is_ascii_whitespace());
            cuts.push(past.map_or(bytes.len(), |k| last + PIECE + k));
        }
        cuts.push(bytes.len());
        cuts.dedup();
        let pieces: Vec<Vec<T>> = (cuts.par_windows(2))
            .map(|w| {
                self.text[w[0]..w[1]]
                    .split_ascii_whitespace()
                    .map(&parse)
                    .collect()
            })
            .collect::<Result<_, E>>()?;
        let mut all = Vec::with_capacity(pieces.iter().map(Vec::len).sum());
        pieces.into_iter().for_each(|p| all.extend(p));
        Ok(all)
    }

    /// How many numbers the list holds.
    pub(super) fn len(&self) -> usize {
        self.text.split_ascii_whitespace().count()
    }
}

/// The length of the number list that `rest` (the text after a `[`) starts with, when it is
/// long enough to keep as text and ends at a `]`.
fn number_list(rest: &str) -> Option<usize> {
    let number_byte = |b: &u8| b.is_ascii_digit() || b.is_ascii_whitespace();
    let end = (rest.as_bytes().iter())
        .position(|b| !(number_byte(b) || matches!(b, b'+' | b'-' | b'.' | b'e' | b'E')))?;
    (end >= NUMBER_LIST_MIN_BYTES && rest.as_bytes()[end] == b']').then_some(end)
}

#[derive(Clone, Debug, PartialEq)]
pub(super) struct Token {
    pub kind: TokenKind,
    /// The file the token was read from.
    pub file: Arc<Path>,
    pub line: usize,
    pub column: usize,
}

/// A lexing error: where, and what.
#[derive(Debug, PartialEq)]
pub(super) struct LexError {
    pub line: usize,
    pub column: usize,
    pub message: String,
}

/// Splits `text`, the contents of `file`, into tokens.
pub(super) fn tokens(text: &str, file: &Arc<Path>) -> Result<Vec<Token>, LexError> {
    let mut out = Vec::new();
    // `as_str` is what is left to read; a clone peeks.
    let mut chars = text.chars();
    let (mut line, mut column) = (1usize, 1usize);
    while let Some(c) = chars.clone().next() {
        let (start_line, start_column) = (line, column);
        let advance = |c: char, line: &mut usize, column: &mut usize| {
            if c == '\n' {
                *line += 1;
                *column = 1;
            } else {
                *column += 1;
            }
        };
        if c.is_whitespace() {
            chars.next();
            advance(c, &mut line, &mut column);
            continue;
        }
        if c == '#' {
            for c in chars.by_ref() {
                advance(c, &mut line, &mut column);
                if c == '\n' {
                    break;
                }
            }
            continue;
        }
        let kind = match c {
            '[' => {
                chars.next();
                column += 1;
                if let Some(end) = number_list(chars.as_str()) {
                    out.push(Token {
                        kind: TokenKind::Open,
                        file: file.clone(),
                        line,
                        column: column - 1,
                    });
                    let (list, rest) = chars.as_str().split_at(end);
                    let (start_line, start_column) = (line, column);
                    // ASCII only: a byte is a column.
                    match list.rfind('\n') {
                        Some(last) => {
                            line += list.bytes().filter(|&b| b == b'\n').count();
                            column = list.len() - last;
                        }
                        None => column += list.len(),
                    }
                    chars = rest.chars();
                    let text = list.to_string();
                    out.push(Token {
                        kind: TokenKind::Numbers(Arc::new(NumberList { text })),
                        file: file.clone(),
                        line: start_line,
                        column: start_column,
                    });
                    continue;
                }
                TokenKind::Open
            }
            ']' => {
                chars.next();
                column += 1;
                TokenKind::Close
            }
            '"' => {
                chars.next();
                column += 1;
                let mut s = String::new();
                loop {
                    let Some(c) = chars.next() else {
                        return Err(LexError {
                            line: start_line,
                            column: start_column,
                            message: "the string that starts here never ends (no closing \")"
                                .into(),
                        });
                    };
                    if c == '\n' {
                        return Err(LexError {
                            line: start_line,
                            column: start_column,
                            message: "the string that starts here runs past the end of its line"
                                .into(),
                        });
                    }
                    advance(c, &mut line, &mut column);
                    match c {
                        '"' => break,
                        '\\' => {
                            let Some(e) = chars.next() else { continue };
                            advance(e, &mut line, &mut column);
                            s.push(match e {
                                'n' => '\n',
                                't' => '\t',
                                other => other,
                            });
                        }
                        other => s.push(other),
                    }
                }
                TokenKind::Str(s)
            }
            _ => {
                let mut word = String::new();
                while let Some(c) = chars.clone().next() {
                    if c.is_whitespace() || matches!(c, '[' | ']' | '"' | '#') {
                        break;
                    }
                    word.push(c);
                    chars.next();
                    column += 1;
                }
                if word.starts_with(|c: char| c.is_ascii_digit() || matches!(c, '-' | '+' | '.')) {
                    TokenKind::Number(word)
                } else {
                    TokenKind::Word(word)
                }
            }
        };
        out.push(Token {
            kind,
            file: file.clone(),
            line: start_line,
            column: start_column,
        });
    }
    Ok(out)
}

/// Tokens of `text` as if read from a file named `test.pbrt`, for tests.
#[cfg(test)]
pub(super) fn test_tokens(text: &str) -> Result<Vec<Token>, LexError> {
    tokens(text, &Arc::from(Path::new("test.pbrt")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(text: &str) -> Vec<TokenKind> {
        test_tokens(text)
            .unwrap()
            .into_iter()
            .map(|t| t.kind)
            .collect()
    }

    #[test]
    fn splits_directives_strings_numbers_and_brackets() {
        assert_eq!(
            kinds("Shape \"sphere\" \"float radius\" [2.5]# a comment\nWorldEnd"),
            vec![
                TokenKind::Word("Shape".into()),
                TokenKind::Str("sphere".into()),
                TokenKind::Str("float radius".into()),
                TokenKind::Open,
                TokenKind::Number("2.5".into()),
                TokenKind::Close,
                TokenKind::Word("WorldEnd".into()),
            ]
        );
    }

    #[test]
    fn positions_are_one_based_lines_and_columns() {
        let t = test_tokens("  Translate 1 -2 .5\n\t\"x\"").unwrap();
        let at: Vec<_> = t.iter().map(|t| (t.line, t.column)).collect();
        assert_eq!(at, vec![(1, 3), (1, 13), (1, 15), (1, 18), (2, 2)]);
    }

    #[test]
    fn an_unterminated_string_names_where_it_starts() {
        let err = test_tokens("Shape \"trianglemesh\n\"x\"").unwrap_err();
        assert_eq!((err.line, err.column), (1, 7));
        let err = test_tokens("Shape \"abc").unwrap_err();
        assert_eq!((err.line, err.column), (1, 7));
    }

    #[test]
    fn a_long_number_list_is_one_token_that_parses_to_what_tokens_a_number_would() {
        let numbers: Vec<String> = (0..3000)
            .map(|i| format!("{}", (i as f32 * 0.37 - 400.0) / 7.0))
            .collect();
        let text = format!("\"point3 P\" [ {}\n]\nWorldEnd", numbers.join("\n "));
        let t = test_tokens(&text).unwrap();
        let TokenKind::Numbers(list) = &t[2].kind else {
            panic!("{:?}", t[2].kind)
        };
        assert_eq!(
            (t[1].kind.clone(), t[3].kind.clone()),
            (TokenKind::Open, TokenKind::Close)
        );
        assert_eq!(
            (t[1].line, t[1].column, t[2].line, t[2].column),
            (1, 12, 1, 13)
        );
        // The `]` and what follows keep their places.
        assert_eq!((t[3].line, t[3].column), (3001, 1));
        assert_eq!((t[4].line, t[4].column), (3002, 1));
        assert_eq!(list.len(), 3000);
        let parsed = list.parse(|w| w.parse::<f32>()).unwrap();
        let one_by_one: Vec<f32> = numbers.iter().map(|w| w.parse().unwrap()).collect();
        assert_eq!(parsed, one_by_one);
        let bad = format!("[{} 1-2 ]", "7 ".repeat(3000));
        let t = test_tokens(&bad).unwrap();
        let TokenKind::Numbers(list) = &t[1].kind else {
            panic!()
        };
        assert!(
            list.parse(|w| w.parse::<i64>().map_err(|_| w.to_string()))
                .unwrap_err()
                == "1-2"
        );
        // A word that is not a number's keeps the list a token a number.
        let word = format!("[{} nan ]", "7 ".repeat(3000));
        assert!(
            !test_tokens(&word)
                .unwrap()
                .iter()
                .any(|t| matches!(t.kind, TokenKind::Numbers(_)))
        );
    }

    #[test]
    fn escapes_are_decoded() {
        assert_eq!(
            kinds(r#""a\"b\\c""#),
            vec![TokenKind::Str("a\"b\\c".into())]
        );
    }
}
