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

#[cfg(test)]
mod tests {
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
