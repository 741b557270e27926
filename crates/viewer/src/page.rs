//! The page: an HTML template with the data, three.js and the viewer's script inlined.

use crate::Scene;

const TEMPLATE: &str = include_str!("page.html");
const VIEWER_JS: &str = include_str!("viewer.js");
const THREE_JS: &str = include_str!("../vendor/three.module.min.js");
/// The version of the vendored three.js (`vendor/README.md`).
pub const THREE_VERSION: &str = "0.170.0";

const DATA_OPEN: &str = "<script type=\"application/json\" id=\"flexmbs-data\">";

/// Text inside a `script` element: what would end it early (`</script`) or switch the parser
/// into its escaped states (`<!--`) is written with a backslash, which JavaScript strings,
/// templates and regular expressions read as the same characters.
fn script_text(js: &str) -> String {
    js.replace("</script", "<\\/script").replace("<!--", "<\\!--")
}

/// Text inside an HTML element: `&`, `<`, `>` as entities.
fn html_text(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// The self-contained page showing `scene`.
pub fn page(scene: &Scene) -> String {
    // JSON text never needs a raw `<`: inside strings it is written `\u003c`.
    let data = serde_json::to_string(scene)
        .expect("the scene is plain data")
        .replace('<', "\\u003c");
    // One pass over the template: a marker inside inserted text is never replaced.
    let mut out = String::with_capacity(TEMPLATE.len() + THREE_JS.len() + VIEWER_JS.len() + data.len());
    let mut rest = TEMPLATE;
    while let Some(start) = rest.find("{{") {
        let end = start + rest[start..].find("}}").expect("template markers are closed") + 2;
        out.push_str(&rest[..start]);
        match &rest[start..end] {
            "{{TITLE}}" => out.push_str(&html_text(&scene.title)),
            "{{THREE_VERSION}}" => out.push_str(THREE_VERSION),
            "{{DATA}}" => out.push_str(&data),
            "{{THREE}}" => out.push_str(&script_text(THREE_JS)),
            "{{VIEWER}}" => out.push_str(&script_text(VIEWER_JS)),
            other => panic!("unknown template marker {other}"),
        }
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// The scene inlined in a page written by [`page`] (to write the page again with this
/// version of the viewer).
pub fn data_of_page(html: &str) -> Result<Scene, String> {
    let start = html
        .find(DATA_OPEN)
        .ok_or("not a flexmbs viewer page: it has no flexmbs-data element")?
        + DATA_OPEN.len();
    let end = html[start..]
        .find("</script>")
        .ok_or("the page's flexmbs-data element is not closed")?;
    serde_json::from_str(&html[start..start + end]).map_err(|e| format!("the page's data cannot be read: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::*;

    fn scene() -> Scene {
        Scene {
            title: "a <b> & c".into(),
            analyses: vec![Analysis {
                name: "run</script>".into(),
                kind: "dynamic".into(),
                bodies: vec![Body {
                    name: "rod".into(),
                    vertices: F32s(vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
                    triangles: U32s(vec![0, 1, 2]),
                    vertex_node: U32s(vec![0, 1, 2]),
                    n_shapes: 1,
                    shapes: F32s(vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1e-3]),
                    ..Default::default()
                }],
                frames: vec![Frame {
                    key: 0.5,
                    poses: vec![Pose::at([1.0, 2.0, 3.0], 1)],
                    markers: Vec::new(),
                }],
                ..Default::default()
            }],
        }
    }

    /// The page holds the data, three.js and the script, nothing that reaches the network,
    /// and gives the scene back whole.
    #[test]
    fn the_page_is_self_contained_and_gives_its_data_back() {
        let s = scene();
        let html = page(&s);
        assert_eq!(data_of_page(&html).unwrap(), s);
        assert!(html.contains("<title>a &lt;b&gt; &amp; c</title>"));
        // One closing tag per script element: the data's `</script>` is escaped.
        assert_eq!(html.matches("</script>").count(), html.matches("<script").count());
        for remote in ["http://", "https://", "//cdn", "src=\"http"] {
            assert!(
                !html.replace(THREE_JS, "").contains(remote),
                "the page refers to {remote}"
            );
        }
        assert!(html.contains("three.js r170") || html.contains(THREE_VERSION));
    }

    #[test]
    fn base64_arrays_keep_their_values() {
        let a = F32s(vec![1.5, -2.25e-7, f32::MAX]);
        let text = serde_json::to_string(&a).unwrap();
        assert_eq!(serde_json::from_str::<F32s>(&text).unwrap(), a);
        let u = U32s(vec![0, 7, u32::MAX]);
        assert_eq!(
            serde_json::from_str::<U32s>(&serde_json::to_string(&u).unwrap()).unwrap(),
            u
        );
        assert!(data_of_page("<html></html>").unwrap_err().contains("flexmbs-data"));
    }
}
