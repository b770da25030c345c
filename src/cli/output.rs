//! Output files: a run directory that one run owns, and files that appear
//! whole or not at all (written to a temporary name, then renamed), so a crash
//! or a second run never leaves a half-written or interleaved file.

use anyhow::{Context, Result, bail};
use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

/// Name of the lock file a run keeps in its output directory while it runs.
pub const LOCK_NAME: &str = ".haptloop-run.lock";

/// The directory this process has claimed and not yet released, and
/// whether the claim created it, so a signal that ends the process can give
/// it back.
static CLAIMED: std::sync::Mutex<Option<(PathBuf, bool)>> = std::sync::Mutex::new(None);

/// Gives back the claimed directory of a run that ends without releasing
/// it: removes its lock and its unfinished `.partial` files, then the
/// directory if the claim created it and nothing else is in it. For the
/// signal handler; a [`RunDir`] that is dropped unreleased does the same.
pub fn abandon_claim() {
    let claimed = CLAIMED.lock().ok().and_then(|mut c| c.take());
    if let Some((dir, created)) = claimed {
        give_back(&dir, created);
    }
}

fn give_back(dir: &Path, created: bool) {
    if let Ok(entries) = fs::read_dir(dir) {
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().ends_with(".partial") {
                let _ = fs::remove_file(e.path());
            }
        }
    }
    let _ = fs::remove_file(dir.join(LOCK_NAME));
    if created {
        let _ = fs::remove_dir(dir); // only succeeds when empty
    }
}

/// An output directory claimed by this run: it was empty (or new) and holds
/// this run's lock file until [`RunDir::release`]. Dropped without a release
/// (an error, an abort), it is given back: lock and unfinished files
/// removed, the directory too if the claim created it and it is empty, so
/// the next run can use it.
#[derive(Debug)]
pub struct RunDir {
    dir: PathBuf,
    created: bool,
    released: bool,
}

impl RunDir {
    /// Claims `dir`: creates it if needed, refuses it if it holds anything
    /// (another run's files, or a run still writing there), then takes the
    /// lock with an exclusive create, so two runs started together cannot both
    /// claim it.
    pub fn claim(dir: &Path) -> Result<RunDir> {
        let created = !dir.exists();
        fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let mut entries =
            fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))?;
        if let Some(entry) = entries.next() {
            let name = entry?.file_name();
            bail!(
                "--out {}: the directory is not empty (it holds `{}`); a run writes only into a new or empty directory so that two runs never mix their files",
                dir.display(),
                name.to_string_lossy()
            );
        }
        OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(dir.join(LOCK_NAME))
            .with_context(|| format!("--out {}: another run claimed it first", dir.display()))?;
        if let Ok(mut c) = CLAIMED.lock() {
            *c = Some((dir.to_path_buf(), created));
        }
        Ok(RunDir {
            dir: dir.to_path_buf(),
            created,
            released: false,
        })
    }

    /// Picks `base`, or `base-2`, `base-3`, … if taken, and claims it.
    pub fn claim_fresh(base: &Path) -> Result<RunDir> {
        for k in 1..1000 {
            let dir = if k == 1 {
                base.to_path_buf()
            } else {
                PathBuf::from(format!("{}-{k}", base.display()))
            };
            if !dir.exists() {
                return RunDir::claim(&dir);
            }
        }
        bail!("no free run directory next to {}", base.display())
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Removes the lock: the run is complete.
    pub fn release(mut self) -> Result<()> {
        if let Ok(mut c) = CLAIMED.lock() {
            c.take();
        }
        self.released = true;
        let lock = self.dir.join(LOCK_NAME);
        fs::remove_file(&lock).with_context(|| format!("removing {}", lock.display()))
    }
}

impl Drop for RunDir {
    fn drop(&mut self) {
        if !self.released {
            if let Ok(mut c) = CLAIMED.lock() {
                c.take();
            }
            give_back(&self.dir, self.created);
        }
    }
}

/// The temporary name `path` is written under before it is renamed.
pub fn partial_name(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    path.with_file_name(name)
}

/// Writes `bytes` to `path` atomically: a temporary file beside it, flushed
/// to disk, then renamed over `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = partial_name(path);
    let mut f = File::create(&tmp).with_context(|| format!("writing {}", tmp.display()))?;
    f.write_all(bytes)
        .and_then(|()| f.sync_all())
        .with_context(|| format!("writing {}", tmp.display()))?;
    fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}

/// Produces `path` atomically with `make`, which writes the file it is given
/// (a temporary name beside `path`).
pub fn produce_atomic(path: &Path, make: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = partial_name(path);
    make(&tmp)?;
    fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}

/// Fails now, before any long work, if a file cannot be created at `path`.
pub fn check_writable(path: &Path) -> Result<()> {
    let tmp = partial_name(path);
    File::create(&tmp).with_context(|| format!("cannot write {}", path.display()))?;
    fs::remove_file(&tmp).with_context(|| format!("cannot write {}", path.display()))
}

/// `YYYYMMDD-HHMMSS` in UTC, for default run directories.
pub fn utc_stamp() -> String {
    let secs = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // Days since 1970-01-01 → civil date (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}{m:02}{d:02}-{:02}{:02}{:02}",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_claimed_directory_refuses_a_second_run_until_released() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("run");
        let first = RunDir::claim(&dir).unwrap();
        let err = RunDir::claim(&dir).unwrap_err().to_string();
        assert!(
            err.contains("not empty") && err.contains(LOCK_NAME),
            "{err}"
        );
        write_atomic(&dir.join("a.txt"), b"whole").unwrap();
        assert_eq!(fs::read(dir.join("a.txt")).unwrap(), b"whole");
        assert!(!partial_name(&dir.join("a.txt")).exists());
        first.release().unwrap();
        // Files of a finished run still make the directory non-empty.
        assert!(RunDir::claim(&dir).is_err());
        let fresh = RunDir::claim_fresh(&dir).unwrap();
        assert_eq!(fresh.path(), tmp.path().join("run-2"));
    }

    /// A claim dropped without a release (an error after the claim) gives
    /// the directory back: no lock, no `.partial` file, and a directory the
    /// claim created is gone; one that existed stays, empty, and can be
    /// claimed again.
    #[test]
    fn an_unreleased_claim_is_given_back() {
        let tmp = tempfile::tempdir().unwrap();
        let new = tmp.path().join("new");
        {
            let d = RunDir::claim(&new).unwrap();
            fs::write(d.path().join("trace.csv.partial"), b"").unwrap();
        }
        assert!(!new.exists());
        let old = tmp.path().join("old");
        fs::create_dir(&old).unwrap();
        {
            let d = RunDir::claim(&old).unwrap();
            write_atomic(&d.path().join("summary.json"), b"{}").unwrap();
            fs::write(d.path().join("force.svg.partial"), b"").unwrap();
        }
        let left: Vec<_> = fs::read_dir(&old)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left, ["summary.json"]);
    }

    #[test]
    fn unwritable_paths_fail_before_work() {
        let tmp = tempfile::tempdir().unwrap();
        assert!(check_writable(&tmp.path().join("ok.json")).is_ok());
        assert!(check_writable(&tmp.path().join("no/such/dir/x.json")).is_err());
        assert!(!tmp.path().join("ok.json.partial").exists());
    }
}
