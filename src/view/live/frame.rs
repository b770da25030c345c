//! The live page's messages: frames out (JSON text), pointer moves in.

use crate::session::{FingerFrame, LiveFrame, LivePointer};
use nalgebra::Vector3;
use serde_json::{Value, json};

/// A frame message from the newest body and finger frames; the events are
/// included when `with_events`.
pub fn encode(bodies: &LiveFrame, fingers: &FingerFrame, with_events: bool) -> String {
    let s = &bodies.sample;
    let poses: Vec<[f64; 7]> = s
        .poses
        .iter()
        .map(|(r, q)| [r[0], r[1], r[2], q[0], q[1], q[2], q[3]])
        .collect();
    let contacts: Vec<[f64; 7]> = s
        .contacts
        .iter()
        .map(|c| {
            let (p, n) = (c.point_m, c.normal);
            [p[0], p[1], p[2], n[0], n[1], n[2], c.gap_m]
        })
        .collect();
    let f: Vec<Value> = fingers
        .fingers
        .iter()
        .map(|f| json!({"device": f.device_m, "tip": f.tip_m, "force": f.force_n}))
        .collect();
    let mut m = json!({
        "type": "frame",
        "t": bodies.t_s.max(fingers.t_s),
        "poses": poses,
        "fingers": f,
        "contacts": contacts,
        "violation": finite(s.violation_m),
    });
    if with_events {
        m["events"] = bodies
            .events
            .iter()
            .map(|e| {
                let text = if e.offer_body.is_empty() {
                    format!("{} {}", e.kind.as_str(), e.binding_body)
                } else {
                    format!("{} {} / {}", e.kind.as_str(), e.binding_body, e.offer_body)
                };
                json!({"t_s": e.t_s, "kind": e.kind.as_str(), "body": e.binding_body, "text": text})
            })
            .collect();
    }
    m.to_string()
}

fn finite(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// Applies a page's message: `{"type":"pointer","device":NAME,"target":[x,y,z]}`
/// (scene frame, m) moves that virtual device's pointer. Returns the index
/// of the device moved, or `None` for anything else (ignored, counted).
pub fn apply(text: &str, pointers: &[LivePointer]) -> Option<usize> {
    let v: Value = serde_json::from_str(text).ok()?;
    if v["type"] != "pointer" {
        return None;
    }
    let name = v["device"].as_str()?;
    let t = v["target"].as_array()?;
    let xyz: Vec<f64> = t.iter().filter_map(Value::as_f64).collect();
    if xyz.len() != 3 || !xyz.iter().all(|x| x.is_finite()) {
        return None;
    }
    let k = pointers.iter().position(|p| p.device == name)?;
    let p = &pointers[k];
    let device = p
        .mount
        .point_to_device(&Vector3::new(xyz[0], xyz[1], xyz[2]));
    p.pointer.set(&device).then_some(k)
}

#[cfg(test)]
mod tests {
    use super::*;
    use haptloop_devices::{Mount, Pointer};

    /// A target in the scene frame lands in the device frame through the
    /// mount (rotated, scaled, registered); junk is refused.
    #[test]
    fn a_pointer_message_moves_the_named_device_through_its_mount() {
        let mut mount = Mount::new(Vector3::zeros(), [0.0, 0.0, 0.0, 1.0], 2.0).unwrap();
        mount.register(&Vector3::zeros(), &Vector3::new(0.1, 0.2, 0.3));
        let pointers = vec![LivePointer {
            device: "right".into(),
            pointer: Pointer::new(),
            mount,
        }];
        let msg = r#"{"type":"pointer","device":"right","target":[0.12,0.2,0.3]}"#;
        assert_eq!(apply(msg, &pointers), Some(0));
        let d = pointers[0].pointer.get().unwrap();
        // 180° about z, scale 2: +2 cm in the scene is −1 cm along device x.
        assert!((d - Vector3::new(-0.01, 0.0, 0.0)).norm() < 1e-6, "{d:?}");
        for bad in [
            r#"{"type":"pointer","device":"left","target":[0,0,0]}"#,
            r#"{"type":"pointer","device":"right","target":[0,0]}"#,
            r#"{"type":"pointer","device":"right","target":[0,"x",0]}"#,
            "not json",
        ] {
            assert_eq!(apply(bad, &pointers), None, "{bad}");
        }
    }
}
