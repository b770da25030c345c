//! A scene's text with its moving bodies moved: the `position` and
//! `orientation` of each `[[body]]` replaced in place (or added after its
//! `name` where the file left them at their defaults), every other byte of
//! the file kept. `haptloop place` writes the placed configuration this way,
//! so the result is a scene that runs from there.

use super::LoadedScene;

/// A body's new pose: name, position (m) and orientation `[w, x, y, z]`.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyPose {
    /// The `[[body]]` name.
    pub name: String,
    /// m, scene frame.
    pub position_m: [f64; 3],
    /// Unit quaternion, `[w, x, y, z]`.
    pub orientation_wxyz: [f64; 4],
}

fn array(xs: &[f64]) -> String {
    let parts: Vec<String> = xs.iter().map(|x| format!("{x:?}")).collect();
    format!("[{}]", parts.join(", "))
}

impl LoadedScene {
    /// The file's text with every body of `poses` at its new pose (see the
    /// module docs). Bodies not named keep their lines.
    pub fn with_poses(&self, poses: &[BodyPose]) -> String {
        // (start, end, replacement), applied from the back.
        let mut edits: Vec<(usize, usize, String)> = Vec::new();
        for b in &self.spec.bodies {
            let Some(pose) = poses.iter().find(|p| &p.name == b.name.get_ref()) else {
                continue;
            };
            let after_name = b.name.span().end;
            let pos = array(&pose.position_m);
            match &b.position {
                Some(p) => edits.push((p.span().start, p.span().end, pos)),
                None => edits.push((after_name, after_name, format!("\nposition = {pos}"))),
            }
            let rot = array(&pose.orientation_wxyz);
            match &b.orientation {
                Some(o) => edits.push((o.span().start, o.span().end, rot)),
                None => edits.push((after_name, after_name, format!("\norientation = {rot}"))),
            }
        }
        edits.sort_by_key(|e| std::cmp::Reverse((e.0, e.1)));
        let mut text = self.text.clone();
        for (start, end, with) in edits {
            text.replace_range(start..end, &with);
        }
        text
    }
}
