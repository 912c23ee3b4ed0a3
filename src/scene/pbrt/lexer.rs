//! pbrt's tokens: quoted strings, numbers, `[` `]`, bare words (directives and `true`/`false`),
//! with `#` comments skipped. Every token carries its file and its 1-based line and column (in
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
    let mut chars = text.chars().peekable();
    let (mut line, mut column) = (1usize, 1usize);
    while let Some(&c) = chars.peek() {
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
            '[' | ']' => {
                chars.next();
                column += 1;
                if c == '[' {
                    TokenKind::Open
                } else {
                    TokenKind::Close
                }
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
                while let Some(&c) = chars.peek() {
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
    fn escapes_are_decoded() {
        assert_eq!(
            kinds(r#""a\"b\\c""#),
            vec![TokenKind::Str("a\"b\\c".into())]
        );
    }
}
