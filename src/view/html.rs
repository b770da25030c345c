//! `view.html`: one self-contained page (styles, three.js, the viewer
//! script and the run's data inlined; no server, no network), built from
//! the assets in `src/view/assets/`, which are compiled into the binary.

use super::data::PageData;
use anyhow::Result;

const TEMPLATE: &str = include_str!("assets/viewer.html");
const STYLE: &str = include_str!("assets/viewer.css");
const VIEWER: &str = include_str!("assets/viewer.js");
/// three.js 0.187.0 with OrbitControls and ConvexGeometry, bundled by
/// `src/view/assets/three/build.sh` (MIT licence beside it).
const THREE: &str = include_str!("assets/three/three.bundle.js");

/// Text that may sit inside a `<script>` element: a `</` would end it.
fn script_safe(text: &str) -> String {
    text.replace("</", "<\\/")
}

/// The page for `data` (a run's files, or the live page's scene).
pub fn page(data: &PageData) -> Result<String> {
    let title = data.scene.as_ref().map_or("", |s| s.scene.as_str());
    let json = script_safe(&serde_json::to_string(data)?);
    // Placeholders are replaced once each, in order, and never searched for
    // again inside what replaced them.
    let mut out = String::with_capacity(TEMPLATE.len() + json.len() + THREE.len() + VIEWER.len());
    let mut rest = TEMPLATE;
    for (key, value) in [
        ("__TITLE__", html_escape(title)),
        ("__STYLE__", STYLE.to_owned()),
        ("__DATA__", json),
        ("__THREE__", script_safe(THREE)),
        ("__VIEWER__", script_safe(VIEWER)),
    ] {
        if let Some(at) = rest.find(key) {
            out.push_str(&rest[..at]);
            out.push_str(&value);
            rest = &rest[at + key.len()..];
        }
    }
    out.push_str(rest);
    Ok(out)
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every placeholder is filled, the data survives a `</script>` in a
    /// name, and nothing in the page reaches for the network.
    #[test]
    fn the_page_is_self_contained() {
        let mut d = PageData::default();
        d.events.push(super::super::data::EventData {
            t_s: 1.0,
            kind: "snap".into(),
            text: "</script><b>".into(),
            body: "</script>".into(),
        });
        let p = page(&d).unwrap();
        // (three.js itself names a global `__THREE__`: not a placeholder.)
        for key in ["__DATA__", "__VIEWER__", "__STYLE__", "__TITLE__"] {
            assert!(!p.contains(key), "{key} left in the page");
        }
        assert_eq!(
            p.matches("</script>").count(),
            3,
            "only the page's own three scripts end"
        );
        let data = p
            .split("<script id=\"data\" type=\"application/json\">")
            .nth(1)
            .unwrap();
        let data = data.split("</script>").next().unwrap();
        let back: serde_json::Value = serde_json::from_str(&data.replace("<\\/", "</")).unwrap();
        assert_eq!(back["events"][0]["text"], "</script><b>");
        for net in ["http://", "https://", "src=\"", "<link"] {
            let hits: Vec<&str> = p
                .match_indices(net)
                .map(|(i, _)| &p[i..(i + 60).min(p.len())])
                .collect();
            assert!(
                hits.iter()
                    .all(|h| h.starts_with("http://www.w3.org")
                        || h.starts_with("https://threejs.org")),
                "the page refers to {net}: {hits:?}"
            );
        }
    }
}
