//! The machine a report was measured on (DEVELOPERS: reports record the
//! machine, medians and spread), as the first rows of a Markdown table.

/// `| machine | |` table rows: date (UTC), CPU model, logical CPUs, OS,
/// rustc version and build profile, then `extra` rows (label, value).
pub fn table(extra: &[(&str, String)]) -> String {
    let mut rows = vec![
        (
            "date (UTC)",
            command_output("date", &["-u", "+%Y-%m-%d %H:%M"]),
        ),
        ("CPU", cpu_model()),
        ("logical CPUs (nproc)", command_output("nproc", &[])),
        ("OS", command_output("uname", &["-sr"])),
        ("rustc", command_output("rustc", &["--version"])),
        (
            "profile",
            if cfg!(debug_assertions) {
                "debug (use --release)".to_string()
            } else {
                "release".to_string()
            },
        ),
    ];
    rows.extend(extra.iter().map(|(k, v)| (*k, v.clone())));
    let mut s = String::from("| machine | |\n|---|---|\n");
    for (k, v) in rows {
        s.push_str(&format!("| {k} | {v} |\n"));
    }
    s
}

/// The 1, 5 and 15 minute load averages (`/proc/loadavg`), or `unknown`.
pub fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

/// The trimmed standard output of a command, or `unknown`.
pub fn command_output(cmd: &str, args: &[&str]) -> String {
    std::process::Command::new(cmd)
        .args(args)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into())
}

/// The CPU model name from `/proc/cpuinfo`, or `unknown`.
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

/// The machine's CPU time so far, all CPUs together, in clock ticks: the
/// `cpu` line of Linux's `/proc/stat`. On a virtual machine `steal` is
/// the time a virtual CPU was ready to run and the hypervisor ran another
/// guest instead: a timed run then takes longer by work nobody on this
/// machine did, which neither the load average nor the run's own CPU
/// time shows. Reports take it before and after each run and print the
/// share ([`CpuTimes::steal_since`]) beside its time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CpuTimes {
    /// Ticks the hypervisor gave to other guests.
    pub steal: u64,
    /// Every tick: user, nice, system, idle, iowait, irq, softirq and
    /// steal (guest time is already counted in user and nice).
    pub total: u64,
}

impl CpuTimes {
    /// The times now, or `None` where `/proc/stat` cannot be read (not
    /// Linux).
    pub fn now() -> Option<CpuTimes> {
        std::fs::read_to_string("/proc/stat")
            .ok()
            .and_then(|text| CpuTimes::parse(&text))
    }

    /// The times of the `cpu` line of `/proc/stat`'s text `stat`; `None`
    /// without one of at least eight counts (kernels before 2.6.11 had no
    /// steal column).
    pub fn parse(stat: &str) -> Option<CpuTimes> {
        let line = stat.lines().find(|l| l.starts_with("cpu "))?;
        let counts: Vec<u64> = line
            .split_whitespace()
            .skip(1)
            .take(8)
            .map(str::parse)
            .collect::<Result<_, _>>()
            .ok()?;
        (counts.len() == 8).then(|| CpuTimes {
            steal: counts[7],
            total: counts.iter().sum(),
        })
    }

    /// The share (0 to 1) of the CPU time from `earlier` to `self` that
    /// was stolen; `None` when no tick passed.
    pub fn steal_since(&self, earlier: &CpuTimes) -> Option<f64> {
        let total = self.total.checked_sub(earlier.total)?;
        let steal = self.steal.checked_sub(earlier.steal)?;
        (total > 0).then(|| steal as f64 / total as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::CpuTimes;

    /// The steal column is the eighth count of the `cpu` line (not a
    /// per-CPU line), the total the sum of the first eight (guest time,
    /// the ninth and tenth, is inside user and nice); the share is the
    /// difference's. A line without a steal column is refused.
    #[test]
    fn steal_is_the_eighth_column_of_the_cpu_line() {
        let before = "cpu  100 0 20 800 5 0 1 74 0 0\ncpu0 50 0 10 400 2 0 0 38 0 0\n";
        let after = "cpu  160 0 30 900 5 0 1 104 9 0\ncpu0 80 0 15 450 2 0 0 53 0 0\n";
        let (a, b) = (
            CpuTimes::parse(before).unwrap(),
            CpuTimes::parse(after).unwrap(),
        );
        assert_eq!(
            a,
            CpuTimes {
                steal: 74,
                total: 1000
            }
        );
        assert_eq!(b.total, 1200);
        assert_eq!(b.steal_since(&a), Some(30.0 / 200.0));
        assert_eq!(a.steal_since(&a), None);
        assert_eq!(a.steal_since(&b), None, "time does not run backwards");
        assert_eq!(CpuTimes::parse("cpu  1 2 3 4 5 6 7\n"), None);
        assert_eq!(CpuTimes::parse("intr 5\n"), None);
    }

    #[test]
    fn table_has_the_common_and_extra_rows() {
        let t = super::table(&[("report wall time", "12 s".into())]);
        for row in [
            "| date (UTC) |",
            "| CPU |",
            "| rustc |",
            "| report wall time | 12 s |",
        ] {
            assert!(t.contains(row), "{t}");
        }
    }
}
