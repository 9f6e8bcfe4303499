//! The tests' own cache folder: before `main` (so before the test harness starts a thread), a
//! test binary points `XDG_CACHE_HOME` at `test-cache` beside its build (`target/<profile>/`),
//! so no test reads or fills the developer's own cache folder, and the commands the tests run
//! inherit it. What is kept there (the materials' surface compliance, the continuum's forces)
//! is checked like every kept file; the first run computes it.

#[cfg(target_os = "linux")]
#[used]
#[unsafe(link_section = ".init_array")]
static BEFORE_MAIN: extern "C" fn() = point_the_cache_at_the_build;

#[cfg(target_os = "linux")]
extern "C" fn point_the_cache_at_the_build() {
    // target/<profile>/deps/<test binary> -> target/<profile>/test-cache
    let Some(dir) = std::env::current_exe().ok().and_then(|e| Some(e.parent()?.parent()?.join("test-cache"))) else {
        return;
    };
    // SAFETY: this runs before `main`, while the process has one thread.
    unsafe { std::env::set_var("XDG_CACHE_HOME", dir) };
}
