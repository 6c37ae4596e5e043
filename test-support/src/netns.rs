//! Networked tests inside a network namespace of their own: DDS discovery sends multicast on
//! every interface it finds, which a test must not do on the machine's network. The test
//! runs its own binary again under `unshare -n` (root, or a user namespace that allows it)
//! with only `lo` up, and the parent waits for that run's result.

use std::process::Command;

/// The variable that marks the run inside the namespace.
const INSIDE: &str = "HAUNTS_TEST_NETNS";

/// Call first in a networked test named `test` (its full name as libtest lists it): `true`
/// inside the namespace (go on), `false` in the parent, which has run the test inside and
/// asserted it passed, or which could not make a namespace (the test is then skipped, with a
/// note on stderr).
///
/// Inside, every interface but `lo` is absent (checked), so nothing leaves the namespace.
pub fn enter(test: &str) -> bool {
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
        eprintln!(
            "skipped {test}: cannot make a network namespace here (unshare -n and ip, as root)"
        );
        return false;
    }
    let exe = std::env::current_exe().expect("the test binary");
    let status = Command::new("unshare")
        .args([
            "-n",
            "--",
            "sh",
            "-c",
            "ip link set lo up && exec \"$0\" \"$@\"",
        ])
        .arg(exe)
        .args([test, "--exact", "--nocapture", "--test-threads=1"])
        .env(INSIDE, "1")
        .status()
        .expect("unshare runs");
    assert!(
        status.success(),
        "{test} failed inside its network namespace"
    );
    false
}
