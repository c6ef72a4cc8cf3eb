//! A panic inside a third-party decoder (its bug on hostile input) caught
//! and turned into the caller's one-line error, without the panic's own
//! report on stderr: a user sees `error: ... the Draco decoder failed on
//! malformed data (...)`, not a backtrace above it.

use std::cell::Cell;
use std::panic::{self, AssertUnwindSafe};
use std::sync::Once;

thread_local! {
    /// Whether this thread is inside `catch_quietly`.
    static QUIET: Cell<bool> = const { Cell::new(false) };
}
static QUIET_HOOK: Once = Once::new();

/// Runs `f`; a panic inside it comes back as `Err` with the panic's
/// message, and is not reported by the panic hook. Panics on other
/// threads, or outside any `catch_quietly`, are reported as before.
pub(crate) fn catch_quietly<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    QUIET_HOOK.call_once(|| {
        let report = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if !QUIET.with(Cell::get) {
                report(info);
            }
        }));
    });
    let outer = QUIET.with(|q| q.replace(true));
    let result = panic::catch_unwind(AssertUnwindSafe(f));
    QUIET.with(|q| q.set(outer));
    result.map_err(|payload| {
        payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::catch_quietly;

    #[test]
    fn a_panic_comes_back_as_its_message() {
        assert_eq!(catch_quietly(|| 7), Ok(7));
        // A message formatted at run time is a String payload (a literal
        // one, even with literal arguments, is a &str).
        let n = std::hint::black_box(1);
        let r: Result<(), String> = catch_quietly(|| panic!("bad {n}"));
        assert_eq!(r, Err("bad 1".to_string()));
        let r: Result<(), String> = catch_quietly(|| panic!("plain"));
        assert_eq!(r, Err("plain".to_string()));
    }
}
