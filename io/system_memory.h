// How much memory this process may still take: the smallest of the machine's available
// memory, the cgroup's limit and the address-space limit (RLIMIT_AS), each counting
// what the process holds already (so it compares with an estimate of its whole peak).
#pragma once

#include <string>

namespace facets {

struct MemoryLimit {
  double mb = 0.0;     // MiB the process as a whole may use
  std::string source;  // "MemAvailable", "cgroup memory.max", "RLIMIT_AS (ulimit -v)"
};

// Reads /proc/meminfo, /sys/fs/cgroup (v2 memory.max or v1 memory.limit_in_bytes, with
// their current usage), getrlimit(RLIMIT_AS) and /proc/self/status. A source that
// cannot be read is left out; none readable gives an infinite limit named "unknown".
MemoryLimit AvailableMemory();

}  // namespace facets
