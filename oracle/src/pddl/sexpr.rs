//! PDDL's surface syntax: nested lists of names, `;` comments to the end of a line, case
//! ignored. Read without recursion and with a bound on nesting, so no text overflows the
//! stack; every node keeps its line for messages.

/// A name or a parenthesised list, with the line it starts on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Node {
    /// A name (`b3`, `on-table`, `:init`), lower-cased; `text` keeps the spelling read.
    Name {
        /// Lower-cased, for matching (PDDL ignores case).
        key: String,
        /// As written.
        text: String,
        /// The line, from 1.
        line: usize,
    },
    /// `( ... )`.
    List {
        /// The items.
        items: Vec<Node>,
        /// The line of the `(`, from 1.
        line: usize,
    },
}

impl Node {
    /// The line this node starts on.
    pub(crate) fn line(&self) -> usize {
        match self {
            Node::Name { line, .. } | Node::List { line, .. } => *line,
        }
    }

    /// The lower-cased name, if this is a name.
    pub(crate) fn key(&self) -> Option<&str> {
        match self {
            Node::Name { key, .. } => Some(key),
            Node::List { .. } => None,
        }
    }

    /// The node as written (lists rebuilt with single spaces), for messages; long lists
    /// are cut.
    pub(crate) fn shown(&self) -> String {
        let mut out = String::new();
        self.show(&mut out);
        if out.chars().count() > 60 {
            let cut: String = out.chars().take(57).collect();
            format!("{cut}...")
        } else {
            out
        }
    }

    fn show(&self, out: &mut String) {
        match self {
            Node::Name { text, .. } => out.push_str(text),
            Node::List { items, .. } => {
                out.push('(');
                for (i, item) in items.iter().enumerate() {
                    if i > 0 {
                        out.push(' ');
                    }
                    if out.len() > 80 {
                        out.push_str("...");
                        break;
                    }
                    item.show(out);
                }
                out.push(')');
            }
        }
    }
}

/// Where a reader is, for messages: the file being read.
pub(crate) struct Source<'a> {
    pub(crate) file: &'a str,
}

impl Source<'_> {
    /// The error of a file that is not what its reader takes, at `line`.
    pub(crate) fn err<T>(&self, line: usize, reason: impl Into<String>) -> crate::error::Result<T> {
        Err(super::error::PddlError::Invalid {
            file: self.file.to_string(),
            line,
            reason: reason.into(),
        }
        .into())
    }
}

/// The deepest nesting read: a problem file nests five deep (`define`, `:goal`, `and`, an
/// atom); anything far deeper is not one.
pub(crate) const MAX_DEPTH: usize = 32;

/// The one top-level list of `text`, a `what` file (`problem` or `domain`, for messages);
/// `Err((line, reason))` for anything else: an unbalanced parenthesis, nesting past
/// [`MAX_DEPTH`], no list, or more than one.
pub(crate) fn parse(text: &str, what: &str) -> Result<Node, (usize, String)> {
    // Open lists, innermost last, each with the line of its '('.
    let mut open: Vec<(Vec<Node>, usize)> = Vec::new();
    let mut top: Vec<Node> = Vec::new();
    let mut line = 1;
    let mut chars = text.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        match c {
            '\n' => line += 1,
            ';' => while chars.next_if(|&(_, c)| c != '\n').is_some() {},
            '(' => {
                if open.len() == MAX_DEPTH {
                    return Err((
                        line,
                        format!("lists nest deeper than {MAX_DEPTH}: this is not a {what} file"),
                    ));
                }
                open.push((Vec::new(), line));
            }
            ')' => {
                let (items, start) = open.pop().ok_or((line, "')' closes no '('".to_string()))?;
                let node = Node::List { items, line: start };
                match open.last_mut() {
                    Some((parent, _)) => parent.push(node),
                    None => top.push(node),
                }
            }
            c if c.is_whitespace() => {}
            _ => {
                let mut end = i + c.len_utf8();
                while let Some(&(j, d)) = chars.peek() {
                    if d.is_whitespace() || matches!(d, '(' | ')' | ';') {
                        break;
                    }
                    end = j + d.len_utf8();
                    chars.next();
                }
                let word = &text[i..end];
                let node = Node::Name {
                    key: word.to_lowercase(),
                    text: word.to_string(),
                    line,
                };
                match open.last_mut() {
                    Some((parent, _)) => parent.push(node),
                    None => return Err((line, format!("{word:?} stands outside any list"))),
                }
            }
        }
    }
    if let Some((_, start)) = open.last() {
        return Err((*start, "this '(' is never closed".to_string()));
    }
    let mut top = top.into_iter();
    match (top.next(), top.next()) {
        (None, _) => Err((
            line,
            format!("the file holds no list: a {what} is (define ({what} NAME) ...)"),
        )),
        (Some(node), None) => Ok(node),
        (Some(_), Some(extra)) => Err((extra.line(), format!("a second list after the {what}'s (define ...)"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(node: &Node) -> String {
        match node {
            Node::Name { key, .. } => key.clone(),
            Node::List { items, .. } => format!("[{}]", items.iter().map(keys).collect::<Vec<_>>().join(" ")),
        }
    }

    #[test]
    fn reads_lists_names_comments_and_case() {
        let node = parse("; head\n(Define (a B)(c) ; note (x\n d)", "problem").unwrap();
        assert_eq!(keys(&node), "[define [a b] [c] d]");
        assert_eq!(node.line(), 2);
        let Node::List { items, .. } = &node else { panic!() };
        assert_eq!(items[3].line(), 3);
        assert_eq!(items[1].shown(), "(a B)");
    }

    #[test]
    fn refuses_unbalanced_deep_empty_and_extra_text() {
        assert_eq!(parse("(a\n(b)", "problem").unwrap_err().0, 1);
        assert!(parse("(a))", "problem").unwrap_err().1.contains("closes no"));
        assert!(
            parse(&"(".repeat(100), "problem")
                .unwrap_err()
                .1
                .contains("nest deeper")
        );
        assert!(parse("; nothing", "problem").unwrap_err().1.contains("no list"));
        assert!(parse("(a) (b)", "problem").unwrap_err().1.contains("second list"));
        assert!(parse("x (a)", "problem").unwrap_err().1.contains("outside any list"));
    }
}
