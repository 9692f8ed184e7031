//! The docs a user reads hold to the lab notebook: each figure the README and the guide
//! (docs/guide/) quote (accuracies with their intervals, multiply-adds, percentages, sizes and
//! times) links on its line to the named section of the notebook (docs/*.md) it comes from, and
//! that section states it; every relative link leads to a file; the pages a user follows say
//! what holds now, not the history of their making; the README stays a five-minute read and each
//! guide page short.

use std::path::Path;

#[path = "support/pages.rs"]
mod pages;
#[path = "support/workspace.rs"]
mod workspace;

use pages::{markdown_in, user_pages};
use workspace::workspace;

/// The targets of the Markdown links in `text`, as written (`path#anchor`).
fn links(text: &str) -> impl Iterator<Item = &str> {
    text.split("](").skip(1).filter_map(|s| s.split_once(')').map(|(t, _)| t))
}

/// Every `a ± b` in `line` (numbers with a decimal point), as written.
fn figures(line: &str) -> Vec<String> {
    let number = |s: &str, from_end: bool| -> String {
        let is_part = |c: char| c.is_ascii_digit() || c == '.';
        let text: String = if from_end {
            s.chars()
                .rev()
                .skip_while(|c| *c == '*' || *c == ' ')
                .take_while(|c| is_part(*c))
                .collect::<Vec<_>>()
                .into_iter()
                .rev()
                .collect()
        } else {
            s.chars().skip_while(|c| *c == ' ').take_while(|c| is_part(*c)).collect()
        };
        text
    };
    let parts: Vec<&str> = line.split('±').collect();
    parts
        .windows(2)
        .map(|w| (number(w[0], true), number(w[1], false)))
        .filter(|(a, b)| a.contains('.') && b.contains('.'))
        .map(|(a, b)| format!("{a} ± {b}"))
        .collect()
}

/// Every `[c, d]` interval in `line`.
fn intervals(line: &str) -> Vec<String> {
    line.split('[')
        .skip(1)
        .filter_map(|s| s.split_once(']').map(|(inside, _)| inside))
        .filter(|inside| inside.split(", ").count() == 2 && inside.split(", ").all(|v| v.parse::<f64>().is_ok()))
        .map(|inside| format!("[{inside}]"))
        .collect()
}

/// The interval written after `figure` in `line`, before any other figure: the figure's own.
fn interval_after(line: &str, figure: &str) -> Option<String> {
    let after = &line[line.find(figure)? + figure.len()..];
    intervals(after.split('±').next().unwrap_or("")).into_iter().next()
}

/// What a quoted figure measures, by its unit.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Accuracy,
    MultiplyAdds,
    Percentage,
    Size,
    Time,
}

/// The units that make a number a figure of each kind (the interval's level, "95 % interval",
/// is a definition, not a figure).
const UNITS: [(&str, Kind); 11] = [
    (" M", Kind::MultiplyAdds),
    (" %", Kind::Percentage),
    (" KiB", Kind::Size),
    (" MiB", Kind::Size),
    (" GiB", Kind::Size),
    (" MB", Kind::Size),
    (" µs", Kind::Time),
    (" ms", Kind::Time),
    (" s", Kind::Time),
    (" minutes", Kind::Time),
    (" hours", Kind::Time),
];

/// `line` as a reader sees its figures: no code spans, no emphasis.
fn plain(line: &str) -> String {
    line.split('`').step_by(2).collect::<Vec<_>>().join("").replace("**", "")
}

/// Every figure `line` quotes, its kind and its text as written.
fn quoted(line: &str) -> Vec<(Kind, String)> {
    let line = plain(line);
    let mut found: Vec<(Kind, String)> = figures(&line).into_iter().map(|f| (Kind::Accuracy, f)).collect();
    let chars: Vec<(usize, char)> = line.char_indices().collect();
    let mut i = 0;
    while i < chars.len() {
        let (at, c) = chars[i];
        let follows_word = i > 0 && (chars[i - 1].1.is_alphanumeric() || chars[i - 1].1 == '.' || chars[i - 1].1 == '±');
        if !c.is_ascii_digit() || follows_word {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < chars.len()
            && (chars[j].1.is_ascii_digit() || (matches!(chars[j].1, '.' | ',') && chars.get(j + 1).is_some_and(|n| n.1.is_ascii_digit())))
        {
            j += 1;
        }
        let end = chars.get(j).map_or(line.len(), |c| c.0);
        let rest = &line[end..];
        let unit = UNITS.iter().find(|(u, _)| {
            rest.starts_with(u) && !rest[u.len()..].starts_with(|c: char| c.is_alphanumeric()) && !rest[u.len()..].starts_with(" interval")
        });
        if let Some((u, kind)) = unit {
            found.push((*kind, format!("{}{u}", &line[at..end])));
        }
        i = j.max(i + 1);
    }
    found
}

/// A heading's anchor, as GitHub makes it: lower case, spaces to hyphens, punctuation dropped.
fn slug(heading: &str) -> String {
    heading
        .trim_start_matches('#')
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The section of `text` under the heading whose anchor is `anchor`, to the next heading of its
/// level or above.
fn section(text: &str, anchor: &str) -> Option<String> {
    let lines: Vec<&str> = text.lines().collect();
    // A heading's level; 0 for any other line, a code block's `#` lines included.
    let mut code = false;
    let levels: Vec<usize> = lines
        .iter()
        .map(|l| {
            code ^= l.starts_with("```");
            if code || !l.starts_with('#') {
                0
            } else {
                l.chars().take_while(|c| *c == '#').count()
            }
        })
        .collect();
    let start = (0..lines.len()).find(|&i| levels[i] > 0 && slug(lines[i]) == anchor)?;
    let end = (start + 1..lines.len()).find(|&i| (1..=levels[start]).contains(&levels[i])).unwrap_or(lines.len());
    Some(lines[start..end].iter().map(|l| plain(l)).collect::<Vec<_>>().join("\n"))
}

/// The homes `line` links to: notebook sections (`page.md#anchor`), read by `read`.
fn homes(line: &str, page: &Path, read: &dyn Fn(&Path) -> Option<String>) -> Vec<(String, Option<String>)> {
    links(line)
        .filter_map(|target| target.split_once('#'))
        .filter(|(path, _)| path.ends_with(".md"))
        .map(|(path, anchor)| {
            let text = read(&page.parent().unwrap().join(path));
            (format!("{path}#{anchor}"), text.and_then(|t| section(&t, anchor)))
        })
        .collect()
}

/// The figures of `text` (a page at `page`) that their home does not state: each line that
/// quotes a figure links to the named section it comes from, and that section states it, an
/// accuracy with the same interval on the same line.
fn unhomed(page: &Path, text: &str, read: &dyn Fn(&Path) -> Option<String>, held: &dyn Fn(&str) -> bool) -> (usize, Vec<String>) {
    let (mut checked, mut wrong) = (0, Vec::new());
    let mut code = false;
    for (n, line) in text.lines().enumerate() {
        code ^= line.starts_with("```");
        let figures = quoted(line);
        if code || figures.is_empty() || line.trim_start().starts_with("<!--") || held(line) {
            continue;
        }
        let homes = homes(line, page, read);
        for (kind, figure) in figures {
            checked += 1;
            let interval = (kind == Kind::Accuracy).then(|| interval_after(&plain(line), &figure)).flatten();
            let stated = |section: &String| {
                section.lines().any(|l| l.contains(&figure) && (interval.is_none() || interval_after(l, &figure) == interval))
            };
            if !homes.iter().any(|(_, s)| s.as_ref().is_some_and(stated)) {
                let to = homes.iter().map(|h| h.0.as_str()).collect::<Vec<_>>().join(", ");
                let why = if homes.is_empty() { "no home linked on its line".to_string() } else { format!("not in {to}") };
                wrong.push(format!("{}:{}: {kind:?} {figure} {}: {why}", page.display(), n + 1, interval.unwrap_or_default()));
            }
        }
    }
    (checked, wrong)
}

#[test]
fn every_figure_a_user_reads_is_its_home_s() {
    let read = |p: &Path| std::fs::read_to_string(p).ok();
    let (mut checked, mut wrong) = (0, Vec::new());
    // The presets table's rows are held to `pvt3 info` instead (below).
    let presets = presets_table();
    let held = |line: &str| presets.contains(&line_cells(line));
    for page in user_pages() {
        let (c, w) = unhomed(&page, &std::fs::read_to_string(&page).unwrap(), &read, &held);
        checked += c;
        wrong.extend(w);
    }
    assert!(checked >= 20, "the pages' figures are read ({checked})");
    assert!(wrong.is_empty(), "figures their home does not state:\n{}", wrong.join("\n"));
}

/// A table row's cells, trimmed.
fn line_cells(line: &str) -> Vec<String> {
    line.split('|').map(|c| c.trim().to_string()).collect()
}

/// The rows of the command-line guide's presets table, as cells: their home is `pvt3 info`.
fn presets_table() -> Vec<Vec<String>> {
    let page = std::fs::read_to_string(workspace().join("docs/guide/command-line.md")).unwrap();
    page.lines()
        .skip_while(|l| !l.starts_with("## Presets"))
        .take_while(|l| !l.starts_with("(`pvt3 info"))
        .filter(|l| l.starts_with("| `"))
        .map(line_cells)
        .collect()
}

/// The presets table is what `pvt3 info PRESET` prints: each row's parameters, and its
/// multiply-adds in millions to the table's one decimal.
#[test]
fn the_presets_table_is_what_pvt3_info_prints() {
    let rows = presets_table();
    assert!(rows.len() >= 7, "the presets table is read: {rows:?}");
    for row in rows {
        let preset = row[1].trim_matches('`');
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_pvt3")).args(["info", preset]).output().unwrap();
        let info = String::from_utf8(out.stdout).unwrap();
        let field = |name: &str| info.lines().find(|l| l.starts_with(name)).and_then(|l| l.split_whitespace().nth(1)).map(str::to_string);
        let parameters = row[4].split_whitespace().next().unwrap_or_default().replace(',', "");
        assert_eq!(Some(parameters), field("parameters"), "{preset}: {info}");
        let multiply_adds: f64 = field("mult-adds").and_then(|m| m.parse().ok()).unwrap_or(f64::NAN);
        assert_eq!(row[5], format!("{:.1} M", multiply_adds / 1e6), "{preset}: {info}");
    }
}

/// A wrong figure of each kind, planted in a page, is found; the right ones pass.
#[test]
fn a_planted_wrong_figure_of_each_kind_fails() {
    let home = "# Notebook\n## The table\n| row | 0.9500 ± 0.0098 | [0.9418, 0.9582] | 6.59 M | 26 % | 8.1 MiB | 124 µs |\n## Other\n0.9600 ± 0.0100\n";
    let read = |p: &Path| p.ends_with("notebook.md").then(|| home.to_string());
    let page = Path::new("docs/guide/page.md");
    let right = "| [row](../notebook.md#the-table) | 0.9500 ± 0.0098 | [0.9418, 0.9582] | 6.59 M | 26 % | 8.1 MiB | 124 µs |";
    assert_eq!(
        unhomed(page, right, &read, &|_| false),
        (5, vec![]),
        "an accuracy with its interval, multiply-adds, a share, a size, a time"
    );
    for (right_figure, wrong_figure) in [
        ("0.9500 ± 0.0098", "0.9500 ± 0.0099"),
        ("[0.9418, 0.9582]", "[0.9418, 0.9583]"),
        ("6.59 M", "6.58 M"),
        ("26 %", "27 %"),
        ("8.1 MiB", "8.2 MiB"),
        ("124 µs", "125 µs"),
    ] {
        let (_, wrong) = unhomed(page, &right.replace(right_figure, wrong_figure), &read, &|_| false);
        assert_eq!(wrong.len(), 1, "{wrong_figure}: {wrong:?}");
    }
    let (_, homeless) = unhomed(page, "It takes 5 minutes.", &read, &|_| false);
    assert!(homeless[0].contains("no home linked"), "{homeless:?}");
    let (_, elsewhere) = unhomed(page, "[x](../notebook.md#other): 0.9500 ± 0.0098", &read, &|_| false);
    assert!(elsewhere[0].contains("not in ../notebook.md#other"), "a figure stated in another section is not at home: {elsewhere:?}");
    assert_eq!(quoted("the 95 % interval, `--set x=5 ms`, x86-64 and 1.18× at 3 × 4"), vec![]);
    assert_eq!(slug("### iCub-20, 3 seeds × 4 folds"), "icub-20-3-seeds--4-folds");
}

#[test]
fn the_figure_reader_reads_figures_and_intervals() {
    let line = "| x | **0.9492 ± 0.0082** | [0.9444, 0.9539] | 0.95 ± 0.01 and ±3 dB [1, 2] |";
    assert_eq!(figures(line), ["0.9492 ± 0.0082", "0.95 ± 0.01"]);
    assert_eq!(intervals(line), ["[0.9444, 0.9539]", "[1, 2]"]);
    assert_eq!(interval_after(line, "0.9492 ± 0.0082").as_deref(), Some("[0.9444, 0.9539]"));
    let another = "(0.9946 ± 0.0045 elsewhere) | **0.9950 ± 0.0043** | [0.9919, 0.9981]";
    assert_eq!(interval_after(another, "0.9946 ± 0.0045"), None, "the interval after another figure is not its");
}

/// The relative links of `text` (a page at `page`): each target as written and the path it leads
/// to (the part before any `#`, from the page's folder).
fn relative_links<'a>(page: &'a Path, text: &'a str) -> impl Iterator<Item = (&'a str, std::path::PathBuf)> + 'a {
    links(text).filter_map(move |target| {
        let path = target.split('#').next().unwrap();
        (!path.is_empty() && !path.contains("://")).then(|| (target, page.parent().unwrap().join(path)))
    })
}

#[test]
fn every_relative_link_a_user_follows_leads_to_a_file() {
    let (mut broken, mut followed) = (Vec::new(), 0);
    for page in user_pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for (target, path) in relative_links(&page, &text) {
            followed += 1;
            if !path.exists() {
                broken.push(format!("{}: {target}", page.display()));
            }
        }
    }
    assert!(followed >= 10, "the pages' relative links are read ({followed})");
    assert!(broken.is_empty(), "links to no file:\n{}", broken.join("\n"));
}

/// What in `line` tells the history of its page's making (an issue, a numbered period of work)
/// where a reader wants what holds now: the words, or `None`.
fn making(line: &str) -> Option<String> {
    let lower = line.to_lowercase();
    let numbered = |word: &str| {
        lower
            .match_indices(word)
            .map(|(i, _)| &lower[i..])
            .find(|rest| rest[word.len()..].trim_start_matches('#').starts_with(|c: char| c.is_ascii_digit()))
    };
    let said = ["the issue", "issue's", "an issue"].into_iter().find_map(|w| lower.find(w).map(|i| &lower[i..]));
    said.or_else(|| numbered("issue ")).or_else(|| numbered("session ")).map(|rest| rest.chars().take(30).collect())
}

/// The pages a user reads and the pages they link to (docs/*.md, the changelog).
fn pages_and_their_links() -> Vec<std::path::PathBuf> {
    let user: Vec<_> = user_pages().into_iter().map(|p| p.canonicalize().unwrap()).collect();
    let mut pages = user.clone();
    for page in &user {
        let text = std::fs::read_to_string(page).unwrap();
        for (_, path) in relative_links(page, &text).filter(|(_, p)| p.extension().is_some_and(|e| e == "md")) {
            let linked = path.canonicalize().unwrap_or_else(|e| panic!("{}: a link to {}: {e}", page.display(), path.display()));
            if !pages.contains(&linked) {
                pages.push(linked);
            }
        }
    }
    pages
}

/// The README, the guide and every page they link to say what holds now: no issue numbers, no
/// "the issue", no numbered periods of work (their history is the notebook's, by date and commit).
#[test]
fn the_pages_a_user_follows_say_what_holds_now() {
    let pages = pages_and_their_links();
    assert!(pages.iter().any(|p| p.ends_with("docs/camera.md")) && pages.iter().any(|p| p.ends_with("CHANGELOG.md")), "{pages:?}");
    let told: Vec<String> = pages
        .iter()
        .flat_map(|page| {
            let text = std::fs::read_to_string(page).unwrap();
            text.lines()
                .enumerate()
                .filter_map(|(i, l)| making(l).map(|m| format!("{}:{}: {m}", page.display(), i + 1)))
                .collect::<Vec<_>>()
        })
        .collect();
    assert!(told.is_empty(), "history of the page's making where a reader wants what holds now:\n{}", told.join("\n"));
    for history in ["Issue #53. Done:", "within the issue's 30", "(session 34)", "issue 12 asks"] {
        assert!(making(history).is_some(), "{history}");
    }
    for now in ["A session of a file runs a third plan", "pvt3_session_push_camera_frame", "an answer's issue"] {
        assert_eq!(making(now), None, "{now}");
    }
}

#[test]
fn the_readme_is_a_five_minute_read_and_each_guide_page_short() {
    let lines = |p: &Path| std::fs::read_to_string(p).unwrap().lines().count();
    assert!(lines(&workspace().join("README.md")) <= 150, "README.md: {} lines", lines(&workspace().join("README.md")));
    let guide = markdown_in(&workspace().join("docs/guide"));
    assert!(guide.len() >= 6, "the guide's pages: {guide:?}");
    for page in guide {
        assert!(lines(&page) <= 300, "{}: {} lines", page.display(), lines(&page));
    }
}
