//! The self-contained `scene.html`: three.js (the bundled parts, MIT licence text
//! inlined beside it), the viewer script and style, the JSON header and the binary
//! arrays as base64, all in one file that opens from disk without a server or a
//! network.

use base64::Engine;

use super::data::ScenePage;
use super::pack::pack;
use crate::ReportError;

/// The three.js parts the page uses, one IIFE defining `window.FATHOM_THREE`
/// (rebuilt by `assets/three/bundle.sh` from the npm packages).
const THREE_BUNDLE: &str = include_str!("../../assets/three/three-bundle.min.js");
/// three.js's licence, shipped inside every page that carries it.
const THREE_LICENSE: &str = include_str!("../../assets/three/LICENSE");
/// The viewer: decodes the data, builds the scene, the slider, the camera.
const VIEWER_JS: &str = include_str!("../../assets/viewer.js");
/// The page's style.
const VIEWER_CSS: &str = include_str!("../../assets/viewer.css");

/// Text that would end a `<script>` or `<style>` element early.
fn guard(name: &str, text: &str) -> Result<(), ReportError> {
    let lower = text.to_ascii_lowercase();
    if lower.contains("</script") || lower.contains("</style") || lower.contains("<!--") {
        return Err(ReportError::invalid_argument(
            format!("scene page part `{name}`"),
            "contains a closing tag or a comment opener and cannot be inlined",
        ));
    }
    Ok(())
}

/// Escapes text for an HTML text node.
fn html_text(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The page of `page`: every scene checked, then thinned for display
/// ([`super::decimate`]), packed and inlined.
///
/// # Errors
/// [`ReportError::InvalidArgument`] for an inconsistent scene or no scene at all.
pub fn scene_html(page: &ScenePage) -> Result<String, ReportError> {
    if page.scenes.is_empty() {
        return Err(ReportError::invalid_argument("scene page", "no scene"));
    }
    for s in &page.scenes {
        s.check()?;
    }
    let thin = ScenePage {
        scenes: page.scenes.iter().map(|s| s.decimated()).collect(),
        ..page.clone()
    };
    let packed = pack(&thin);
    // `<` appears in JSON only inside strings, where `\u003c` means the same.
    let header = packed.header.to_string().replace('<', "\\u003c");
    let data = base64::engine::general_purpose::STANDARD.encode(&packed.bytes);
    for (name, text) in [
        ("three.js", THREE_BUNDLE),
        ("viewer.js", VIEWER_JS),
        ("viewer.css", VIEWER_CSS),
    ] {
        guard(name, text)?;
    }
    let title = html_text(&page.title);
    let mut html = String::with_capacity(THREE_BUNDLE.len() + data.len() + 32 * 1024);
    html.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    html.push_str(&format!(
        "<title>{title}</title>\n<style>\n{VIEWER_CSS}\n</style>\n"
    ));
    html.push_str("</head>\n<body>\n<div id=\"app\"></div>\n");
    html.push_str(&format!(
        "<script type=\"application/json\" id=\"fathom-header\">{header}</script>\n"
    ));
    html.push_str(&format!(
        "<script type=\"application/octet-stream\" id=\"fathom-data\">{data}</script>\n"
    ));
    html.push_str(&format!(
        "<script type=\"text/plain\" id=\"three-license\">\nthree.js r187, bundled: \
         the parts fathom's scene page uses.\n{}\n</script>\n",
        html_text(THREE_LICENSE)
    ));
    html.push_str(&format!("<script>\n{THREE_BUNDLE}\n</script>\n"));
    html.push_str(&format!(
        "<script>\n{VIEWER_JS}\n</script>\n</body>\n</html>\n"
    ));
    Ok(html)
}

#[cfg(test)]
mod tests {
    use super::super::data::tests_support::small_scene;
    use super::*;

    /// The page carries the library, its licence, the viewer and the data; a scene
    /// name cannot close the data's script element.
    #[test]
    fn page_inlines_library_licence_and_data() {
        let mut s = small_scene();
        s.name = "</script><b>".into();
        let page = ScenePage {
            title: "a & b".into(),
            note: String::new(),
            scenes: vec![s],
        };
        let html = scene_html(&page).unwrap();
        assert!(html.contains("Copyright © 2010-2026 three.js authors"));
        assert!(html.contains("FATHOM_THREE"));
        assert!(html.contains("<title>a &amp; b</title>"));
        assert_eq!(html.matches("</script>").count(), 5);
        assert!(html.contains("\\u003c/script>\\u003cb>"));
    }

    /// No scene, or an inconsistent one, is an error and not an empty page.
    #[test]
    fn empty_or_inconsistent_pages_are_refused() {
        let mut page = ScenePage {
            title: "t".into(),
            note: String::new(),
            scenes: Vec::new(),
        };
        assert!(scene_html(&page).is_err());
        let mut s = small_scene();
        s.truth.pop();
        page.scenes.push(s);
        assert!(scene_html(&page).is_err());
    }
}
