//! Fault injection for the kill-and-resume test (tests/kill_resume.rs): `PVT3_CRASH_AT=STAGE:N`
//! aborts the process the N-th time a run passes STAGE, with no unwinding and no flush, as a
//! SIGKILL or a power cut would, at a moment a random kill seldom hits (between two renames).
//! Unset, [`point`] does nothing.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

/// The environment variable that names the stage and the pass.
pub const CRASH_AT: &str = "PVT3_CRASH_AT";

/// Aborts here if `CRASH_AT` names `stage` and this is its pass.
pub fn point(stage: &str) {
    static AT: OnceLock<Option<(String, usize)>> = OnceLock::new();
    static PASSES: AtomicUsize = AtomicUsize::new(0);
    let at = AT.get_or_init(|| {
        let value = std::env::var(CRASH_AT).ok()?;
        let (stage, pass) = value.rsplit_once(':')?;
        Some((stage.to_string(), pass.parse().ok()?))
    });
    if let Some((name, pass)) = at {
        if name == stage && PASSES.fetch_add(1, Ordering::SeqCst) + 1 == *pass {
            std::process::abort();
        }
    }
}
