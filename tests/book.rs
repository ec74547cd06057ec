//! The user guide (`docs/book`): its generated pages are what the binary
//! writes now, `mdbook build` succeeds, and every link of the built pages
//! and of the README resolves (files and `#anchors`).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

const BOOK: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/book");

fn shadowlab(args: &[&str]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

/// The pages `scripts/book.sh` writes from the code.
#[test]
fn generated_pages_match_the_code() {
    for (page, args) in [
        (
            "src/techniques/parameters.md",
            &["techniques", "--markdown"][..],
        ),
        ("src/cli-reference.md", &["cli-markdown"][..]),
    ] {
        let committed = std::fs::read_to_string(Path::new(BOOK).join(page)).unwrap();
        assert!(
            committed == shadowlab(args),
            "docs/book/{page} is stale: run scripts/book.sh"
        );
    }
}

/// Every `href="…"` and `src="…"` value of an HTML page.
fn links(html: &str) -> Vec<String> {
    let mut found = vec![];
    for attr in ["href=\"", "src=\""] {
        let mut rest = html;
        while let Some(i) = rest.find(attr) {
            rest = &rest[i + attr.len()..];
            let end = rest.find('"').unwrap_or(rest.len());
            found.push(rest[..end].to_string());
            rest = &rest[end..];
        }
    }
    found
}

fn has_anchor(html: &str, anchor: &str) -> bool {
    html.contains(&format!("id=\"{anchor}\"")) || html.contains(&format!("name=\"{anchor}\""))
}

fn html_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            html_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "html") {
            out.push(p);
        }
    }
}

#[test]
fn the_book_builds_and_every_link_resolves() {
    let mdbook = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/mdbook/bin/mdbook");
    assert!(
        mdbook.is_file(),
        "{} missing: scripts/setup.sh --test installs it",
        mdbook.display()
    );
    let out = common::tmpdir("book");
    let o = Command::new(&mdbook)
        .args(["build", BOOK, "--dest-dir"])
        .arg(&out)
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "mdbook build failed:\n{log}");
    assert!(!log.contains("WARN") && !log.contains("ERROR"), "{log}");
    let mut pages = vec![];
    html_files(&out, &mut pages);
    let chapters = pages
        .iter()
        .filter(|p| {
            !["404.html", "print.html", "toc.html"]
                .contains(&p.file_name().unwrap().to_str().unwrap())
        })
        .count();
    assert!(chapters >= 12, "{chapters} pages");
    let mut broken = vec![];
    for page in &pages {
        let html = std::fs::read_to_string(page).unwrap();
        for link in links(&html) {
            // The 404 page links to the site's root, known only when served.
            if link.contains("://")
                || link.starts_with("mailto:")
                || link.starts_with("data:")
                || link.starts_with('/')
            {
                continue;
            }
            let (file, anchor) = link.split_once('#').unwrap_or((&link, ""));
            let target = if file.is_empty() {
                page.clone()
            } else {
                page.parent().unwrap().join(file)
            };
            let ok = target.is_file()
                && (anchor.is_empty()
                    || target.extension().is_none_or(|x| x != "html")
                    || has_anchor(&std::fs::read_to_string(&target).unwrap(), anchor));
            if !ok {
                broken.push(format!(
                    "{}: {link}",
                    page.strip_prefix(&out).unwrap().display()
                ));
            }
        }
    }
    broken.sort();
    broken.dedup();
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

/// The README's relative links point at files of the repository.
#[test]
fn the_readme_links_resolve() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let mut broken = vec![];
    let mut rest = readme.as_str();
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        let end = rest.find(')').unwrap_or(rest.len());
        let link = &rest[..end];
        let file = link.split('#').next().unwrap();
        if !link.contains("://") && !file.is_empty() && !root.join(file).exists() {
            broken.push(link.to_string());
        }
    }
    assert!(
        broken.is_empty(),
        "README links to missing files: {broken:?}"
    );
}
