//! The crate is built in floors: each module imports only from the floors below it, so it can be
//! read, tested and changed with nothing above it in mind. A cycle in the module import graph
//! means two floors each need the other, and neither can be understood (or moved) alone.
//!
//! This test reads the sources under `src/` with the standard library alone: it maps every file
//! to its module, finds the `crate::`, `super::` and `self::` paths in its code (comments and
//! literals blanked out first), resolves each to the deepest module that exists, and looks for
//! strongly connected components in the graph those references make. A module and its own
//! ancestors or descendants are one floor's inside, not two floors, so those references are
//! left out. The command line (`src/main.rs`, `src/cli/`) is the roof: it may import anything,
//! and nothing imports from it, so it is not read.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

/// A module's path below the crate root: `[]` is the crate, `["render", "plan"]` is
/// `render::plan`.
type ModulePath = Vec<String>;

/// One source file: where it is (relative to the repository root) and the module it defines.
struct Source {
    file: String,
    module: ModulePath,
}

/// One word or punctuation mark of the blanked code, with its 1-based line.
struct Token<'a> {
    text: &'a str,
    line: usize,
}

/// A path found in a file's code, e.g. `super::plan::Pass`, split into its segments, with the
/// line it starts on.
struct Reference<'a> {
    segments: Vec<&'a str>,
    line: usize,
    /// The inline modules (`mod tests { ... }`) the path is written in, outermost first.
    inline: Vec<&'a str>,
}

/// Where one module refers to another: the file, the line, its text, and the inline module the
/// reference is written in, if any.
#[derive(PartialEq)]
struct Site {
    file: String,
    line: usize,
    text: String,
    inline: Vec<String>,
}

/// The modules and the references between them, at the granularity of files.
struct Graph {
    modules: Vec<ModulePath>,
    edges: BTreeMap<(usize, usize), Vec<Site>>,
}

/// No module imports, through any chain of others, a module that imports it back; on failure,
/// each cycle with the file and line of every reference inside it.
#[test]
fn the_crate_s_modules_import_one_another_without_a_cycle() {
    let root = repository_root();
    let graph = import_graph(&root);
    let cycles: Vec<Vec<usize>> =
        strongly_connected_components(&graph).into_iter().filter(|component| component.len() > 1).collect();
    println!(
        "{} modules, {} edges between modules, {} components with a cycle",
        graph.modules.len(),
        graph.edges.len(),
        cycles.len()
    );
    assert!(cycles.is_empty(), "the module imports form {} cycle(s):\n{}", cycles.len(), describe(&graph, &cycles));
}

/// The most lines a source file may have: past it, a file holds more than one concept.
const MAX_FILE_LINES: usize = 700;

#[test]
fn no_source_file_is_over_700_lines() {
    let mut files = Vec::new();
    rust_files(&repository_root().join("src"), &mut files);
    let long: Vec<String> = files
        .iter()
        .map(|f| (f, fs::read_to_string(f).expect("a readable source file").lines().count()))
        .filter(|(_, lines)| *lines > MAX_FILE_LINES)
        .map(|(f, lines)| format!("{}: {lines} lines", f.display()))
        .collect();
    assert!(long.is_empty(), "over {MAX_FILE_LINES} lines:\n{}", long.join("\n"));
}

/// The repository root: cargo's manifest folder, or the current folder when the test was built
/// with plain `rustc`.
fn repository_root() -> PathBuf {
    option_env!("CARGO_MANIFEST_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::current_dir().expect("the current folder"))
}

/// Reads every module under `root/src` and the references between them.
fn import_graph(root: &Path) -> Graph {
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    let sources: Vec<Source> = files
        .iter()
        .filter_map(|path| path.strip_prefix(root).ok())
        .filter(|relative| !is_command_line(relative))
        .map(|relative| Source { file: relative.display().to_string(), module: module_of(relative) })
        .collect();
    assert!(!sources.is_empty(), "no sources under {}", root.join("src").display());
    let modules: Vec<ModulePath> = sources.iter().map(|source| source.module.clone()).collect();
    let index: BTreeMap<&[String], usize> =
        modules.iter().enumerate().map(|(i, module)| (module.as_slice(), i)).collect();
    let mut edges: BTreeMap<(usize, usize), Vec<Site>> = BTreeMap::new();
    for (from, source) in sources.iter().enumerate() {
        let text = fs::read_to_string(root.join(&source.file)).expect("a readable source file");
        let code = blank_comments_and_literals(&text);
        let tokens = tokenize(&code);
        let lines: Vec<&str> = text.lines().collect();
        for reference in references(&tokens) {
            let Some(target) = resolve(&source.module, &reference, &index) else { continue };
            if related(&source.module, &modules[target]) {
                continue;
            }
            let site = Site {
                file: source.file.clone(),
                line: reference.line,
                text: lines.get(reference.line - 1).map_or_else(String::new, |line| line.trim().to_owned()),
                inline: reference.inline.iter().map(ToString::to_string).collect(),
            };
            let sites = edges.entry((from, target)).or_default();
            if !sites.contains(&site) {
                sites.push(site);
            }
        }
    }
    Graph { modules, edges }
}

/// Collects the `.rs` files under `dir`, recursively, in a stable order.
fn rust_files(dir: &Path, files: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = fs::read_dir(dir)
        .expect("a readable source folder")
        .map(|entry| entry.expect("a folder entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            rust_files(&path, files);
        } else if path.extension().is_some_and(|extension| extension == "rs") {
            files.push(path);
        }
    }
}

/// Whether `relative` (e.g. `src/cli/render.rs`) is part of the command line, which may import
/// anything.
fn is_command_line(relative: &Path) -> bool {
    relative == Path::new("src/main.rs") || relative.starts_with("src/cli")
}

/// The module a file defines: `src/lib.rs` is the crate, `src/render/plan/mod.rs` is
/// `render::plan`, `src/render/renderer/record.rs` is `render::renderer::record`.
fn module_of(relative: &Path) -> ModulePath {
    let below_src = relative.strip_prefix("src").unwrap_or(relative).with_extension("");
    let mut module: ModulePath =
        below_src.components().map(|component| component.as_os_str().to_string_lossy().into_owned()).collect();
    if module.last().is_some_and(|last| last == "mod" || (last == "lib" && module.len() == 1)) {
        module.pop();
    }
    module
}

/// The code with every comment (doc comments included), string and character literal replaced
/// by spaces, its line breaks kept so that lines still count the same. A string that is a path
/// and nothing else, as in `#[serde(with = "super::json_null::infinite_as_null")]`, names a
/// module the code uses: only its quotes are blanked.
fn blank_comments_and_literals(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut code = String::with_capacity(text.len());
    let mut i = 0;
    while i < chars.len() {
        let end = comment_or_literal_end(&chars, i);
        if end == i {
            code.push(chars[i]);
            i += 1;
            continue;
        }
        match &chars[i..end] {
            ['"', inner @ .., '"'] if is_path(inner) => {
                code.push(' ');
                code.extend(inner);
                code.push(' ');
            }
            literal => code.extend(literal.iter().map(|&c| if c == '\n' { '\n' } else { ' ' })),
        }
        i = end;
    }
    code
}

/// Whether `text` is a path from `crate`, `super` or `self` and nothing else: `super::a::b`.
fn is_path(text: &[char]) -> bool {
    let text: String = text.iter().collect();
    let mut segments = text.split("::");
    segments.next().is_some_and(|first| ["crate", "super", "self"].contains(&first))
        && text.contains("::")
        && segments.all(|segment| !segment.is_empty() && segment.chars().all(is_word_char))
}

/// Where the comment or literal that starts at `i` ends, or `i` when none starts there.
fn comment_or_literal_end(chars: &[char], i: usize) -> usize {
    let next = chars.get(i + 1).copied();
    let starts_word = i == 0 || !is_word_char(chars[i - 1]);
    match (chars[i], next) {
        ('/', Some('/')) => chars[i..].iter().position(|&c| c == '\n').map_or(chars.len(), |n| i + n),
        ('/', Some('*')) => block_comment_end(chars, i),
        ('"', _) => quoted_end(chars, i + 1),
        ('\'', _) => char_literal_end(chars, i),
        ('r', Some('"' | '#')) if starts_word => raw_string_end(chars, i, i + 1),
        ('b', Some('r')) if starts_word => raw_string_end(chars, i, i + 2),
        ('b', Some('"')) if starts_word => quoted_end(chars, i + 2),
        ('b', Some('\'')) if starts_word => char_literal_end(chars, i + 1),
        _ => i,
    }
}

/// Whether `c` can be part of an identifier or a number.
fn is_word_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The end of the `/* ... */` comment at `start`, nested comments included.
fn block_comment_end(chars: &[char], start: usize) -> usize {
    let (mut depth, mut i) = (0, start);
    while i + 1 < chars.len() {
        match (chars[i], chars[i + 1]) {
            ('/', '*') => (depth, i) = (depth + 1, i + 2),
            ('*', '/') if depth == 1 => return i + 2,
            ('*', '/') => (depth, i) = (depth - 1, i + 2),
            _ => i += 1,
        }
    }
    chars.len()
}

/// The end of the string whose text starts at `i`, just after its opening quote.
fn quoted_end(chars: &[char], mut i: usize) -> usize {
    while i < chars.len() {
        match chars[i] {
            '\\' => i += 2,
            '"' => return i + 1,
            _ => i += 1,
        }
    }
    chars.len()
}

/// The end of the character literal at `quote`, or `quote` itself for a lifetime (`'a`).
fn char_literal_end(chars: &[char], quote: usize) -> usize {
    match (chars.get(quote + 1), chars.get(quote + 2)) {
        (Some('\\'), _) => {
            let rest = chars.get(quote + 3..).unwrap_or_default();
            rest.iter().position(|&c| c == '\'').map_or(chars.len(), |n| quote + n + 4)
        }
        (Some(_), Some('\'')) => quote + 3,
        _ => quote,
    }
}

/// The end of the raw string (`r#"..."#`) that starts at `start` and whose hashes start at
/// `hashes`, or `start` when it is not one (a raw identifier such as `r#type`, or a word).
fn raw_string_end(chars: &[char], start: usize, hashes: usize) -> usize {
    let count = chars[hashes..].iter().take_while(|&&c| c == '#').count();
    if chars.get(hashes + count) != Some(&'"') {
        return start;
    }
    let mut i = hashes + count + 1;
    while i < chars.len() {
        if chars[i] == '"' && chars[i + 1..].iter().take(count).filter(|&&c| c == '#').count() == count {
            return i + 1 + count;
        }
        i += 1;
    }
    chars.len()
}

/// Splits blanked code into words, `::` and single punctuation marks.
fn tokenize(code: &str) -> Vec<Token<'_>> {
    let bytes = code.as_bytes();
    let is_word = |b: u8| b.is_ascii_alphanumeric() || b == b'_' || !b.is_ascii();
    let (mut tokens, mut line, mut i) = (Vec::new(), 1, 0);
    while i < bytes.len() {
        let end = match bytes[i] {
            b'\n' => {
                line += 1;
                i += 1;
                continue;
            }
            b if b.is_ascii_whitespace() => {
                i += 1;
                continue;
            }
            b if is_word(b) => i + bytes[i..].iter().take_while(|&&b| is_word(b)).count(),
            b':' if bytes.get(i + 1) == Some(&b':') => i + 2,
            _ => i + 1,
        };
        tokens.push(Token { text: &code[i..end], line });
        i = end;
    }
    tokens
}

/// Every path that starts with `crate`, `super` or `self` in the tokens, grouped uses
/// (`use super::{a::B, c}`) split into one path each, with the inline modules it is written in.
fn references<'a>(tokens: &[Token<'a>]) -> Vec<Reference<'a>> {
    let text = |i: usize| tokens.get(i).map(|token| token.text);
    let (mut found, mut inline, mut depth, mut i) = (Vec::new(), Vec::<(&str, usize)>::new(), 0, 0);
    while i < tokens.len() {
        match tokens[i].text {
            "{" => depth += 1,
            "}" => {
                depth -= 1;
                if inline.last().is_some_and(|&(_, opened_at)| opened_at == depth) {
                    inline.pop();
                }
            }
            "mod" if text(i + 2) == Some("{") => inline.push((tokens[i + 1].text, depth)),
            "crate" | "super" | "self" if text(i + 1) == Some("::") && (i == 0 || text(i - 1) != Some("::")) => {
                let (line, mut paths) = (tokens[i].line, Vec::new());
                use_tree(tokens, &mut i, Vec::new(), &mut paths);
                let names: Vec<&str> = inline.iter().map(|&(name, _)| name).collect();
                found.extend(paths.into_iter().map(|segments| Reference { segments, line, inline: names.clone() }));
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    found
}

/// Reads the path (or `{ ... }` group of paths) at `tokens[*i]`, after the segments in `prefix`,
/// into `paths`; leaves `*i` just past it.
fn use_tree<'a>(tokens: &[Token<'a>], i: &mut usize, mut prefix: Vec<&'a str>, paths: &mut Vec<Vec<&'a str>>) {
    while let Some(token) = tokens.get(*i) {
        match token.text {
            "{" => {
                *i += 1;
                while tokens.get(*i).is_some_and(|token| token.text != "}") {
                    let before = *i;
                    use_tree(tokens, i, prefix.clone(), paths);
                    if tokens.get(*i).is_some_and(|token| token.text == "as") {
                        *i += 2;
                    }
                    if *i == before || tokens.get(*i).is_some_and(|token| token.text == ",") {
                        *i += 1;
                    }
                }
                *i += 1;
                return;
            }
            word if word.starts_with(|c: char| c.is_alphabetic() || c == '_') => {
                prefix.push(word);
                *i += 1;
                if tokens.get(*i).is_some_and(|token| token.text == "::") {
                    *i += 1;
                    continue;
                }
            }
            "*" => *i += 1,
            _ => {}
        }
        break;
    }
    if !prefix.is_empty() {
        paths.push(prefix);
    }
}

/// The deepest existing module that `reference`, written in `module`, names: `crate`, `self`
/// and each `super` (an inline module's first) pick the start, then each segment that is a
/// module goes one deeper.
fn resolve(module: &[String], reference: &Reference, index: &BTreeMap<&[String], usize>) -> Option<usize> {
    let (first, rest) = reference.segments.split_first()?;
    let mut base: ModulePath = match *first {
        "crate" => Vec::new(),
        "self" => module.to_vec(),
        "super" => {
            let supers = 1 + rest.iter().take_while(|&&segment| segment == "super").count();
            let above_file = supers.saturating_sub(reference.inline.len());
            module[..module.len().checked_sub(above_file)?].to_vec()
        }
        _ => return None,
    };
    for segment in rest.iter().skip_while(|&&segment| segment == "super") {
        base.push(segment.to_string());
        if !index.contains_key(base.as_slice()) {
            base.pop();
            break;
        }
    }
    index.get(base.as_slice()).copied()
}

/// Whether one module is the other, or contains it: a parent and its child are one floor.
fn related(a: &[String], b: &[String]) -> bool {
    a.starts_with(b) || b.starts_with(a)
}

/// The graph's strongly connected components (Tarjan's algorithm), each a list of modules.
fn strongly_connected_components(graph: &Graph) -> Vec<Vec<usize>> {
    let mut successors = vec![Vec::new(); graph.modules.len()];
    for &(from, to) in graph.edges.keys() {
        successors[from].push(to);
    }
    let mut tarjan = Tarjan {
        successors,
        order: vec![None; graph.modules.len()],
        lowest: vec![0; graph.modules.len()],
        on_stack: vec![false; graph.modules.len()],
        stack: Vec::new(),
        next: 0,
        components: Vec::new(),
    };
    for module in 0..graph.modules.len() {
        if tarjan.order[module].is_none() {
            tarjan.visit(module);
        }
    }
    tarjan.components
}

/// Tarjan's strongly connected components: the state of one depth-first search.
struct Tarjan {
    successors: Vec<Vec<usize>>,
    order: Vec<Option<usize>>,
    lowest: Vec<usize>,
    on_stack: Vec<bool>,
    stack: Vec<usize>,
    next: usize,
    components: Vec<Vec<usize>>,
}

impl Tarjan {
    /// Visits `module` and what it reaches, closing a component at each root it finds.
    fn visit(&mut self, module: usize) {
        self.order[module] = Some(self.next);
        self.lowest[module] = self.next;
        self.next += 1;
        self.stack.push(module);
        self.on_stack[module] = true;
        for k in 0..self.successors[module].len() {
            let successor = self.successors[module][k];
            match self.order[successor] {
                None => {
                    self.visit(successor);
                    self.lowest[module] = self.lowest[module].min(self.lowest[successor]);
                }
                Some(order) if self.on_stack[successor] => self.lowest[module] = self.lowest[module].min(order),
                Some(_) => {}
            }
        }
        if Some(self.lowest[module]) == self.order[module] {
            let mut component = Vec::new();
            while let Some(member) = self.stack.pop() {
                self.on_stack[member] = false;
                component.push(member);
                if member == module {
                    break;
                }
            }
            component.sort_unstable();
            self.components.push(component);
        }
    }
}

/// Each cycle's modules and, for every reference inside it, the file and line that makes it.
fn describe(graph: &Graph, cycles: &[Vec<usize>]) -> String {
    let mut text = String::new();
    for (n, cycle) in cycles.iter().enumerate() {
        let names: Vec<String> = cycle.iter().map(|&module| display(&graph.modules[module])).collect();
        let _ = writeln!(text, "\ncycle {}: {}", n + 1, names.join(", "));
        let members: BTreeSet<usize> = cycle.iter().copied().collect();
        for (&(from, to), sites) in &graph.edges {
            if !(members.contains(&from) && members.contains(&to)) {
                continue;
            }
            let _ = writeln!(text, "  {} -> {}", display(&graph.modules[from]), display(&graph.modules[to]));
            for site in sites {
                let inline = if site.inline.is_empty() {
                    String::new()
                } else {
                    format!(" (in mod {})", site.inline.join("::"))
                };
                let _ = writeln!(text, "      {}:{}{inline}: {}", site.file, site.line, site.text);
            }
        }
    }
    text
}

/// A module's path as Rust writes it: `crate`, or `render::plan`.
fn display(module: &[String]) -> String {
    if module.is_empty() { "crate".to_owned() } else { module.join("::") }
}
