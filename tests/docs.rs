//! The docs a user reads hold to the lab notebook: the README and the guide (docs/guide/) quote
//! no figure that its home in the notebook (docs/*.md) does not state, a figure's interval
//! beside it; every relative link leads to a file; the README stays a five-minute read and
//! each guide page short.

use std::path::{Path, PathBuf};

#[path = "support/workspace.rs"]
mod workspace;

use workspace::workspace;

/// The pages a user reads: the README and the guide's.
fn user_pages() -> Vec<PathBuf> {
    let mut pages = vec![workspace().join("README.md")];
    pages.extend(markdown_in(&workspace().join("docs/guide")));
    pages
}

fn markdown_in(dir: &Path) -> Vec<PathBuf> {
    let mut pages: Vec<PathBuf> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "md")).collect();
    pages.sort();
    pages
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

#[test]
fn every_figure_a_user_reads_is_its_notebook_home_s() {
    let notebook: Vec<String> = markdown_in(&workspace().join("docs"))
        .iter()
        .flat_map(|p| std::fs::read_to_string(p).unwrap().lines().map(str::to_string).collect::<Vec<_>>())
        .collect();
    let mut wrong = Vec::new();
    let mut checked = 0;
    for page in user_pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for (n, line) in text.lines().enumerate() {
            for figure in figures(line) {
                checked += 1;
                // Where the page gives the figure's interval, its home gives the same one.
                let interval = interval_after(line, &figure);
                let home = notebook.iter().any(|l| l.contains(&figure) && (interval.is_none() || interval_after(l, &figure) == interval));
                if !home {
                    wrong.push(format!("{}:{}: {figure} {}", page.display(), n + 1, interval.unwrap_or_default()));
                }
            }
        }
    }
    assert!(checked >= 9, "the README's results table is read ({checked} figures)");
    assert!(wrong.is_empty(), "figures no notebook line of docs/*.md states (with their interval):\n{}", wrong.join("\n"));
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

#[test]
fn every_relative_link_a_user_follows_leads_to_a_file() {
    let (mut broken, mut followed) = (Vec::new(), 0);
    for page in user_pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for target in text.split("](").skip(1).filter_map(|s| s.split_once(')').map(|(t, _)| t)) {
            let path = target.split('#').next().unwrap();
            if path.is_empty() || path.contains("://") {
                continue;
            }
            followed += 1;
            if !page.parent().unwrap().join(path).exists() {
                broken.push(format!("{}: {target}", page.display()));
            }
        }
    }
    assert!(followed >= 10, "the pages' relative links are read ({followed})");
    assert!(broken.is_empty(), "links to no file:\n{}", broken.join("\n"));
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
