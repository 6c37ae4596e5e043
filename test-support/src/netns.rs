//! Networked tests inside a network namespace of their own: DDS discovery sends multicast on
//! every interface it finds, which a test must not do on the machine's network. The test
//! runs its own binary again under `unshare -n` (root, or a user namespace that allows it)
//! with only `lo` up, and the parent waits for that run's result.

use std::process::Command;

/// The variable that marks the run inside the namespace.
const INSIDE: &str = "HAUNTS_TEST_NETNS";

/// Set (by `.ci/run` where it can make namespaces), a test that cannot make one fails
/// rather than skips.
const REQUIRE: &str = "HAUNTS_REQUIRE_NETNS";

/// Call first in a networked test named `test` (its full name as libtest lists it): `true`
/// inside the namespace (go on), `false` in the parent, which has run the test inside and
/// asserted it passed, or which could not make a namespace (the test is then skipped, with a
/// note on stderr; with `HAUNTS_REQUIRE_NETNS` set, it fails instead).
///
/// Inside, every interface but `lo` is absent (checked), so nothing leaves the namespace.
pub fn enter(test: &str) -> bool {
    enter_with(test, &[test, "--exact", "--nocapture", "--test-threads=1"])
}

/// [`enter`] for a benchmark binary (`harness = false`): inside the namespace it runs again
/// with the arguments it was given (criterion's), and `name` is what a skip's note calls it.
pub fn enter_bench(name: &str) -> bool {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    enter_with(name, &args)
}

/// `true` inside the namespace; otherwise runs this binary with `args` inside one (asserting
/// it succeeded) and `false`, or `false` with a note when no namespace can be made.
fn enter_with(name: &str, args: &[&str]) -> bool {
    if std::env::var_os(INSIDE).is_some() {
        // /proc/self/net is the namespace's own (/sys/class/net is the mount's, the host's).
        let interfaces: Vec<String> = std::fs::read_to_string("/proc/self/net/dev")
            .unwrap_or_default()
            .lines()
            .filter_map(|l| l.split_once(':').map(|(name, _)| name.trim().to_owned()))
            .collect();
        assert_eq!(interfaces, ["lo"], "the namespace has other interfaces");
        return true;
    }
    let probe = Command::new("unshare")
        .args(["-n", "--", "ip", "link", "set", "lo", "up"])
        .output();
    if !probe.is_ok_and(|o| o.status.success()) {
        assert!(
            std::env::var_os(REQUIRE).is_none(),
            "{name}: cannot make a network namespace (unshare -n and ip, as root), and \
             {REQUIRE} is set"
        );
        eprintln!(
            "skipped {name}: cannot make a network namespace here (unshare -n and ip, as root)"
        );
        return false;
    }
    let exe = std::env::current_exe().expect("the binary running");
    let status = Command::new("unshare")
        .args([
            "-n",
            "--",
            "sh",
            "-c",
            "ip link set lo up && exec \"$0\" \"$@\"",
        ])
        .arg(exe)
        .args(args)
        .env(INSIDE, "1")
        .status()
        .expect("unshare runs");
    assert!(
        status.success(),
        "{name} failed inside its network namespace"
    );
    false
}
