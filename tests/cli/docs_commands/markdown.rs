//! The documents' markdown read as the runner needs it: the `sh` blocks with their marks,
//! the figures the prose quotes, and each command made runnable (see the parent module's
//! header for what a line may say and what each mark means).

/// One line of a block, continuations joined, its comment removed.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// 1-based line in the document where the command starts.
    pub number: usize,
    pub text: String,
}

/// The marks above a block.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Marks {
    pub skip: Option<String>,
    pub skip_prefixes: Vec<(String, String)>,
    pub with: Vec<(String, String)>,
    pub copy: Vec<(String, String)>,
    pub folder: Option<String>,
    pub name: Option<String>,
}

/// A fenced `sh` block.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    /// 1-based line of its opening fence.
    pub fence: usize,
    pub marks: Marks,
    pub lines: Vec<Line>,
}

/// A figure the prose quotes from a named block's output.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    pub number: usize,
    pub value: String,
    pub block: String,
}

/// The `sh` blocks and quoted figures of a document; errors name the line.
pub fn parse(text: &str) -> Result<(Vec<Block>, Vec<Figure>), String> {
    let mut blocks = Vec::new();
    let mut figures = Vec::new();
    let mut marks = Marks::default();
    let lines: Vec<&str> = text.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let trimmed = line.trim();
        if let Some(mark) = trimmed
            .strip_prefix("<!-- doc-test:")
            .and_then(|m| m.strip_suffix("-->"))
        {
            parse_mark(mark.trim(), &mut marks).map_err(|e| format!("line {}: {e}", i + 1))?;
            i += 1;
            continue;
        }
        for (at, _) in line.match_indices("<!-- doc-figure:") {
            let rest = &line[at + "<!-- doc-figure:".len()..];
            let block = rest
                .split("-->")
                .next()
                .map(str::trim)
                .filter(|b| !b.is_empty() && rest.contains("-->"))
                .ok_or_else(|| format!("line {}: a doc-figure mark names no block", i + 1))?;
            let value = last_number(&line[..at])
                .ok_or_else(|| format!("line {}: no number before the doc-figure mark", i + 1))?;
            figures.push(Figure {
                number: i + 1,
                value,
                block: block.to_string(),
            });
        }
        if let Some(lang) = trimmed.strip_prefix("```") {
            let fence = i + 1;
            let mut body = Vec::new();
            i += 1;
            while i < lines.len() && !lines[i].trim_start().starts_with("```") {
                body.push((i + 1, lines[i]));
                i += 1;
            }
            if lang.trim() == "sh" {
                blocks.push(Block {
                    fence,
                    marks: std::mem::take(&mut marks),
                    lines: join_lines(&body),
                });
            } else if marks != Marks::default() {
                return Err(format!(
                    "line {fence}: doc-test marks on a block that is not `sh`"
                ));
            }
            marks = Marks::default();
        } else if !trimmed.is_empty() && marks != Marks::default() {
            return Err(format!(
                "line {}: doc-test marks must stand just above a ```sh block",
                i + 1
            ));
        }
        i += 1;
    }
    Ok((blocks, figures))
}

fn parse_mark(mark: &str, marks: &mut Marks) -> Result<(), String> {
    let pair = |s: &str| {
        s.split_once('=')
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .filter(|(a, b)| !a.is_empty() && !b.is_empty())
            .ok_or_else(|| format!("`{s}`: expected NAME=VALUE"))
    };
    if let Some(rest) = mark.strip_prefix("skip") {
        let rest = rest.trim_start();
        if let Some(why) = rest.strip_prefix(':') {
            let why = why.trim();
            if why.is_empty() {
                return Err("skip: say why".into());
            }
            marks.skip = Some(why.to_string());
            return Ok(());
        }
        let quoted = rest
            .strip_prefix('`')
            .and_then(|r| r.split_once('`'))
            .ok_or("expected `skip: WHY` or ``skip `PREFIX`: WHY``")?;
        let why = quoted.1.trim_start().strip_prefix(':').map(str::trim);
        match why {
            Some(why) if !why.is_empty() => {
                marks
                    .skip_prefixes
                    .push((quoted.0.to_string(), why.to_string()));
                Ok(())
            }
            _ => Err(format!("skip `{}`: say why", quoted.0)),
        }
    } else if let Some(rest) = mark.strip_prefix("with ") {
        for word in rest.split_whitespace() {
            marks.with.push(pair(word)?);
        }
        Ok(())
    } else if let Some(rest) = mark.strip_prefix("copy ") {
        for word in rest.split_whitespace() {
            marks.copy.push(pair(word)?);
        }
        Ok(())
    } else if let Some(rest) = mark.strip_prefix("folder ") {
        marks.folder = Some(rest.trim().to_string());
        Ok(())
    } else if let Some(rest) = mark.strip_prefix("name ") {
        marks.name = Some(rest.trim().to_string());
        Ok(())
    } else {
        Err(format!(
            "unknown doc-test mark `{mark}` (skip, with, copy, folder, name)"
        ))
    }
}

/// The last number in `text` (digits with an optional sign and decimal point).
fn last_number(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut end = bytes.len();
    while end > 0 && !bytes[end - 1].is_ascii_digit() {
        end -= 1;
    }
    if end == 0 {
        return None;
    }
    let mut start = end;
    while start > 0 && (bytes[start - 1].is_ascii_digit() || bytes[start - 1] == b'.') {
        start -= 1;
    }
    if start > 0 && bytes[start - 1] == b'-' {
        start -= 1;
    }
    Some(text[start..end].trim_start_matches('.').to_string())
}

/// Whether a skip mark's `prefix` names `command`: its beginning, or with a final `$`
/// the whole of it.
pub fn skips(prefix: &str, command: &str) -> bool {
    match prefix.strip_suffix('$') {
        Some(whole) => command == whole,
        None => command.starts_with(prefix),
    }
}

/// Joins continuation lines and drops comments and blank lines.
fn join_lines(body: &[(usize, &str)]) -> Vec<Line> {
    let mut out: Vec<Line> = Vec::new();
    let mut open: Option<Line> = None;
    for &(number, raw) in body {
        let text = strip_comment(raw);
        let (text, continues) = match text.trim_end().strip_suffix('\\') {
            Some(t) => (t.to_string(), true),
            None => (text.trim_end().to_string(), false),
        };
        let line = match open.take() {
            Some(mut l) => {
                l.text.push(' ');
                l.text.push_str(text.trim());
                l
            }
            None => Line {
                number,
                text: text.trim().to_string(),
            },
        };
        if continues {
            open = Some(line);
        } else if !line.text.is_empty() {
            out.push(line);
        }
    }
    out.extend(open.filter(|l| !l.text.is_empty()));
    out
}

/// `line` without a shell comment (a `#` that starts a word outside quotes).
fn strip_comment(line: &str) -> String {
    let mut quote = None;
    let mut prev = ' ';
    for (i, c) in line.char_indices() {
        match (quote, c) {
            (None, '\'' | '"') => quote = Some(c),
            (Some(q), c) if c == q => quote = None,
            (None, '#') if prev.is_whitespace() => return line[..i].to_string(),
            _ => {}
        }
        prev = c;
    }
    line.to_string()
}

/// A command made runnable, and the flags its optional parts name.
#[derive(Debug, PartialEq)]
pub struct Runnable {
    pub command: String,
    pub optional_flags: Vec<String>,
}

/// Reads a documented command as the module's header says.
pub fn runnable(text: &str, with: &[(String, String)]) -> Runnable {
    let mut optional_flags = Vec::new();
    // Optional groups, nested or not, each starting a word.
    let mut kept = String::new();
    let mut depth = 0usize;
    let mut group = String::new();
    let mut prev = ' ';
    for c in text.chars() {
        if c == '[' && (depth > 0 || prev.is_whitespace()) {
            depth += 1;
        } else if c == ']' && depth > 0 {
            depth -= 1;
            if depth == 0 {
                optional_flags.extend(
                    group
                        .split(|c: char| c.is_whitespace() || c == '[' || c == ']')
                        .filter(|w| w.starts_with("--"))
                        .map(str::to_string),
                );
                group.clear();
            }
        } else if depth > 0 {
            group.push(c);
        } else {
            kept.push(c);
        }
        prev = c;
    }
    let mut words: Vec<String> = kept.split_whitespace().map(str::to_string).collect();
    if words.len() >= 4 && words[..4] == ["cargo", "run", "--release", "--"] {
        words.splice(..4, ["metamer".to_string()]);
    }
    let simulated = |model: &str| format!("'sim:{model}?time_scale=0'");
    for i in 0..words.len() {
        let w = &words[i];
        if w.contains('|') && w != "|" && w != "||" && !w.starts_with('\'') && !w.starts_with('"') {
            words[i] = w.split('|').next().unwrap_or_default().to_string();
        }
        if let Some((_, value)) = with.iter().find(|(name, _)| *name == words[i]) {
            words[i] = value.clone();
        }
        let flag = if i > 0 { words[i - 1].as_str() } else { "" };
        let w = words[i].as_str();
        let replaced = match flag {
            "--instrument" | "--spectral" | "--spot" if w.starts_with("cs100a") => {
                Some(simulated("cs100a"))
            }
            "--instrument" | "--spectral" | "--spot" if w == "i1pro" || w.starts_with("i1pro:") => {
                Some(simulated("i1pro"))
            }
            "--display" if w == "window" || w.starts_with("window:") => {
                Some("virtual:ips-lcd".to_string())
            }
            _ => None,
        };
        if let Some(r) = replaced {
            words[i] = r;
        }
    }
    Runnable {
        command: words.join(" "),
        optional_flags,
    }
}

/// The subcommand words of a `metamer` command: those after `metamer` up to the first
/// that is not a plain lower-case word.
pub fn subcommand(command: &str) -> Vec<String> {
    command
        .split_whitespace()
        .skip(1)
        .take_while(|w| {
            !w.is_empty()
                && w.chars().all(|c| c.is_ascii_lowercase() || c == '-')
                && !w.starts_with('-')
        })
        .map(str::to_string)
        .collect()
}

/// Whether `text` holds `number` as a whole number: not part of a longer one.
pub fn contains_number(text: &str, number: &str) -> bool {
    text.match_indices(number).any(|(i, _)| {
        let mut before = text[..i].chars().rev();
        let mut after = text[i + number.len()..].chars();
        let digit = |c: Option<char>| c.is_some_and(|c| c.is_ascii_digit());
        let (b1, b2) = (before.next(), before.next());
        let (a1, a2) = (after.next(), after.next());
        let longer_before = digit(b1) || (b1 == Some('.') && digit(b2));
        let longer_after = digit(a1) || (a1 == Some('.') && digit(a2));
        !longer_before && !longer_after
    })
}

#[test]
fn a_documented_command_is_read_as_its_header_says() {
    let with = [(
        "FILE.ti3".to_string(),
        "tests/data/dispread_cal.ti3".to_string(),
    )];
    assert_eq!(
        runnable(
            "metamer fit --measurements FILE.ti3|FILE.csv --model plcc|lut [--folds 5] \
             -o P.json [--icc OUT.icc [--icc-version 4|2.4]] [--force]",
            &with
        ),
        Runnable {
            command:
                "metamer fit --measurements tests/data/dispread_cal.ti3 --model plcc -o P.json"
                    .into(),
            optional_flags: vec![
                "--folds".into(),
                "--icc".into(),
                "--icc-version".into(),
                "--force".into()
            ],
        }
    );
    assert_eq!(
        runnable(
            "cargo run --release -- experiment -o exp/ --spectral i1pro --spot cs100a:/dev/ttyUSB0 --display window:1",
            &[]
        )
        .command,
        "metamer experiment -o exp/ --spectral 'sim:i1pro?time_scale=0' --spot \
         'sim:cs100a?time_scale=0' --display virtual:ips-lcd"
    );
    // Simulated specs and redirections are left as written.
    assert_eq!(
        runnable(
            "metamer spot --instrument 'sim:i1pro?time_scale=0' --json > a.json",
            &[]
        )
        .command,
        "metamer spot --instrument 'sim:i1pro?time_scale=0' --json > a.json"
    );
    assert_eq!(
        subcommand("metamer render spots-from-image image.exr"),
        ["render", "spots-from-image"]
    );
}

#[test]
fn marks_blocks_and_figures_are_read_from_the_markdown() {
    let doc = "text\n\
               <!-- doc-test: skip `metamer b`: it needs hardware -->\n\
               <!-- doc-test: with X=1 Y=2 -->\n\
               \n\
               ```sh\n\
               metamer a --x \\\n    --y   # a comment\n\
               metamer b\n\
               ```\n\
               It prints 0.25 <!-- doc-figure: a --> and -3 in all.<!-- doc-figure: a -->\n\
               ```json\n\
               {}\n\
               ```\n";
    let (blocks, figures) = parse(doc).unwrap();
    assert_eq!(blocks.len(), 1);
    assert_eq!(blocks[0].fence, 5);
    assert_eq!(
        blocks[0].lines,
        [
            Line {
                number: 6,
                text: "metamer a --x --y".into()
            },
            Line {
                number: 8,
                text: "metamer b".into()
            }
        ]
    );
    assert_eq!(
        blocks[0].marks.skip_prefixes,
        [("metamer b".to_string(), "it needs hardware".to_string())]
    );
    assert_eq!(blocks[0].marks.with.len(), 2);
    assert_eq!(
        figures
            .iter()
            .map(|f| (f.number, f.value.as_str()))
            .collect::<Vec<_>>(),
        [(10, "0.25"), (10, "-3")]
    );
    assert!(parse("<!-- doc-test: skip: -->\n```sh\nx\n```\n")
        .unwrap_err()
        .contains("say why"));
    assert!(parse("<!-- doc-test: skip: why -->\ntext\n```sh\nx\n```\n")
        .unwrap_err()
        .starts_with("line 2: doc-test marks must stand just above"));
    assert!(skips("metamer b", "metamer b --json"));
    assert!(skips("metamer b$", "metamer b"));
    assert!(!skips("metamer b$", "metamer b --json"));
    assert!(contains_number("mean 0.25, max 0.84.", "0.25"));
    assert!(contains_number("mean 0.25, max 0.84.", "0.84"));
    assert!(!contains_number("mean 0.253", "0.25"));
    assert!(!contains_number("mean 10.25", "0.25"));
}
