//! A study's texts (consent, instructions) are Markdown, rendered here to HTML that runs
//! nothing: raw HTML in the text is shown as text, links go only to `http`, `https` and
//! `mailto` addresses (a `javascript:` link is shown as its words), and images are shown as
//! their description (a page that fetches nothing of another site's). An ethics board
//! reads the same words the participant does.

use pulldown_cmark::{Event, Options, Parser, Tag, TagEnd, html};

/// `text` as HTML, safely (module docs).
pub fn render(text: &str) -> String {
    let mut links = Vec::new();
    let events = Parser::new_ext(text, Options::ENABLE_TABLES | Options::ENABLE_STRIKETHROUGH).filter_map(|event| {
        match event {
            Event::Html(raw) | Event::InlineHtml(raw) => Some(Event::Text(raw)),
            Event::Start(Tag::Link {
                link_type,
                dest_url,
                title,
                id,
            }) => {
                let safe = is_safe_link(&dest_url);
                links.push(safe);
                safe.then_some(Event::Start(Tag::Link {
                    link_type,
                    dest_url,
                    title,
                    id,
                }))
            }
            Event::End(TagEnd::Link) => links.pop().unwrap_or(false).then_some(Event::End(TagEnd::Link)),
            // The image's description comes as text between these: it stays.
            Event::Start(Tag::Image { .. }) | Event::End(TagEnd::Image) => None,
            other => Some(other),
        }
    });
    let mut out = String::new();
    html::push_html(&mut out, events);
    out
}

fn is_safe_link(dest: &str) -> bool {
    let d = dest.trim().to_ascii_lowercase();
    ["http://", "https://", "mailto:"].iter().any(|p| d.starts_with(p)) || d.starts_with('#')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_becomes_html_and_nothing_in_it_runs() {
        let html = render("# Consent\n\nYou may **stop** at any time: [our page](https://lab.example.org).\n");
        assert!(html.contains("<h1>Consent</h1>"), "{html}");
        assert!(html.contains("<strong>stop</strong>"), "{html}");
        assert!(
            html.contains("<a href=\"https://lab.example.org\">our page</a>"),
            "{html}"
        );
        for attack in [
            "<script>alert(1)</script>",
            "<img src=x onerror=alert(1)>",
            "[click](javascript:alert(1))",
            "![x](https://evil.example/track.png)",
            "<a href=\"javascript:alert(1)\">x</a>",
        ] {
            let html = render(attack);
            assert!(!html.contains("<script"), "{attack} -> {html}");
            assert!(!html.contains("<img"), "{attack} -> {html}");
            assert!(!html.contains("<a href=\"javascript"), "{attack} -> {html}");
        }
        assert!(render("<script>x</script>").contains("&lt;script&gt;"));
    }
}
