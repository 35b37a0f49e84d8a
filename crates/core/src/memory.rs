//! Memory the process can still get, and checks before large allocations, so that a stage
//! too big for the machine fails with [`Error::OutOfMemory`] instead of aborting the process
//! inside the allocator.
//!
//! The room left is the smallest of: physical memory available to new allocations
//! (`MemAvailable` + free swap), the address space left under `RLIMIT_AS` (`ulimit -v`)
//! and the cgroup's memory limit. Where none of these can be read (not Linux), checks pass.

#[cfg(test)]
use crate::error::human;
use crate::error::{Error, Result};

/// Headroom kept free for everything not estimated (thread stacks, allocator arenas,
/// driver mappings): a check fails when the estimate plus this exceeds the room left.
const RESERVE: u64 = 256 << 20;

/// Bytes the process can still allocate, if that can be read on this system.
pub fn available() -> Option<u64> {
    let physical = meminfo("MemAvailable:").map(|a| a + meminfo("SwapFree:").unwrap_or(0));
    let address_space = address_space_limit().map(|limit| {
        let used = status("VmSize:").unwrap_or(0);
        limit.saturating_sub(used)
    });
    let cgroup = cgroup_room();
    [physical, address_space, cgroup]
        .into_iter()
        .flatten()
        .min()
}

/// Fails with [`Error::OutOfMemory`] when `needed` bytes (plus a reserve) are more than the
/// process can still get. `what` names the allocation in the message.
pub fn check(what: impl FnOnce() -> String, needed: u64) -> Result<()> {
    match available() {
        Some(room) if needed.saturating_add(RESERVE) > room => Err(Error::OutOfMemory {
            what: what(),
            needed,
            available: room,
        }),
        _ => Ok(()),
    }
}

/// Bytes of `n` values of `T`, saturating.
pub fn bytes_of<T>(n: u64) -> u64 {
    n.saturating_mul(std::mem::size_of::<T>() as u64)
}

/// A vector with room for `n` values, or [`Error::OutOfMemory`] when the allocation fails
/// (instead of the allocator's abort).
pub fn try_with_capacity<T>(n: usize, what: impl FnOnce() -> String) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| Error::OutOfMemory {
        what: what(),
        needed: bytes_of::<T>(n as u64),
        available: available().unwrap_or(0),
    })?;
    Ok(v)
}

/// A `key: value kB` line of a /proc file, in bytes.
fn kb_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kb: u64 = line[key.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kb.saturating_mul(1024))
}

fn meminfo(key: &str) -> Option<u64> {
    kb_field(&std::fs::read_to_string("/proc/meminfo").ok()?, key)
}

fn status(key: &str) -> Option<u64> {
    kb_field(&std::fs::read_to_string("/proc/self/status").ok()?, key)
}

/// The soft `RLIMIT_AS` in bytes (`None` when unlimited or unreadable).
fn address_space_limit() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// Room under the cgroup (v2) memory limit, if there is one.
fn cgroup_room() -> Option<u64> {
    let read = |f: &str| std::fs::read_to_string(format!("/sys/fs/cgroup/{f}")).ok();
    let max: u64 = read("memory.max")?.trim().parse().ok()?;
    let current: u64 = read("memory.current")?.trim().parse().ok()?;
    Some(max.saturating_sub(current))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units() {
        assert_eq!(human(512), "512 B");
        assert_eq!(human(3 << 29), "1.5 GiB");
    }

    #[test]
    fn absurd_requests_fail_and_small_ones_pass() {
        if available().is_none() {
            return; // nothing to check against on this system
        }
        assert!(check(|| "nothing".into(), 1 << 20).is_ok());
        let e = check(|| "everything".into(), u64::MAX / 2).unwrap_err();
        assert!(e.to_string().contains("everything"), "{e}");
        assert!(try_with_capacity::<u64>(usize::MAX / 16, || "huge".into()).is_err());
    }
}
