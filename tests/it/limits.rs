//! Every file read is bounded: a scene, a hand trace or a replay trace that
//! is too large, or a device that never ends (`/dev/zero`), is refused with
//! its size (or the limit it passed) instead of being read into memory.

use haptloop::scenes::BUILTIN;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs `haptloop args…`, killed if it takes longer than 60 s (an unbounded
/// read of `/dev/zero` would never end).
fn bounded(args: &[&std::ffi::OsStr]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_haptloop"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("haptloop {args:?} was still reading after 60 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

fn os(s: &str) -> &std::ffi::OsStr {
    std::ffi::OsStr::new(s)
}

/// A file of `bytes` zero bytes (sparse: no disk space taken).
fn sparse(path: &Path, bytes: u64) {
    std::fs::File::create(path).unwrap().set_len(bytes).unwrap();
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn oversized_and_endless_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    // Scene files: 4 MiB at most.
    let big = dir.path().join("big.toml");
    sparse(&big, 5 << 20);
    let o = bounded(&[os("check"), big.as_os_str()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("it is 5.2 MB (5242880 bytes); a scene file may be at most 4 MiB"),
        "{}",
        stderr(&o)
    );
    let o = bounded(&[os("check"), os("/dev/zero")]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("holds more than 4 MiB"),
        "{}",
        stderr(&o)
    );
    // Hand traces: 64 MiB at most, read line by line.
    let four_bar = BUILTIN.iter().find(|b| b.name == "four-bar").unwrap().text;
    let circle = four_bar.lines().find(|l| l.starts_with("hand = ")).unwrap();
    let huge = dir.path().join("huge.csv");
    sparse(&huge, 65 << 20);
    for (trace, want) in [
        (
            huge.display().to_string(),
            "is 68.2 MB (68 157 440 bytes); a hand trace may be at most 64 MiB".to_string(),
        ),
        (
            "/dev/zero".to_string(),
            "/dev/zero:1: the line is longer than 4096 bytes".to_string(),
        ),
    ] {
        let scene = dir.path().join("traced.toml");
        std::fs::write(
            &scene,
            four_bar.replace(circle, &format!("hand = {{ trace = \"{trace}\" }}")),
        )
        .unwrap();
        let o = bounded(&[os("check"), scene.as_os_str()]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(&want), "{trace}: {}", stderr(&o));
    }
    // Device traces for a replay: 512 MiB at most.
    for (source, want) in [
        (
            "sparse",
            "is 537.9 MB (537 919 488 bytes); a device trace may be at most 512 MiB",
        ),
        (
            "/dev/zero",
            "right.trace:1: the line is longer than 4096 bytes",
        ),
    ] {
        let traces = dir.path().join(format!("traces-{}", source.len()));
        std::fs::create_dir_all(&traces).unwrap();
        let file = traces.join("right.trace");
        if source == "sparse" {
            sparse(&file, 513 << 20);
        } else {
            std::os::unix::fs::symlink(source, &file).unwrap();
        }
        let o = bounded(&[
            os("run"),
            os("four-bar"),
            os("--deterministic"),
            os("--seconds"),
            os("0.1"),
            os("--no-files"),
            os("--replay"),
            traces.as_os_str(),
        ]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(want), "{source}: {}", stderr(&o));
    }
}
