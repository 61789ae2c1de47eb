#include "io/system_memory.h"

#include <sys/resource.h>

#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

namespace facets {
namespace {

constexpr double kMiB = 1024.0 * 1024.0;

// The value in kB of `key:` in a /proc file of "key: value kB" lines.
std::optional<double> ProcKb(const std::string& file, const std::string& key) {
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key + ":", 0) != 0) continue;
    std::istringstream value(line.substr(key.size() + 1));
    double kb = 0.0;
    if (value >> kb) return kb;
  }
  return std::nullopt;
}

// A number of bytes alone in a file ("max" or a missing file: none).
std::optional<double> FileBytes(const std::string& file) {
  std::ifstream in(file);
  double bytes = 0.0;
  if (!(in >> bytes)) return std::nullopt;
  return bytes;
}

// The cgroup's limit less what its processes use, MiB; none when unlimited.
std::optional<double> CgroupFreeMb() {
  for (const auto& [limit_file, usage_file] :
       {std::pair<std::string, std::string>{"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"},
        {"/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes"}}) {
    const std::optional<double> limit = FileBytes(limit_file);
    // cgroup v1 writes "no limit" as a number near 2^63.
    if (!limit || *limit >= 1e18) continue;
    return (*limit - FileBytes(usage_file).value_or(0.0)) / kMiB;
  }
  return std::nullopt;
}

}  // namespace

MemoryLimit AvailableMemory() {
  MemoryLimit limit{std::numeric_limits<double>::infinity(), "unknown"};
  const double resident_mb = ProcKb("/proc/self/status", "VmRSS").value_or(0.0) / 1024.0;
  auto consider = [&](double free_mb, const std::string& source) {
    if (free_mb + resident_mb < limit.mb) limit = {free_mb + resident_mb, source};
  };
  if (const auto available_kb = ProcKb("/proc/meminfo", "MemAvailable")) consider(*available_kb / 1024.0, "MemAvailable");
  if (const auto cgroup_mb = CgroupFreeMb()) consider(*cgroup_mb, "cgroup memory limit");
  rlimit address_space{};
  if (getrlimit(RLIMIT_AS, &address_space) == 0 && address_space.rlim_cur != RLIM_INFINITY) {
    // Address space already reserved counts against the limit, resident or not.
    const double virtual_mb = ProcKb("/proc/self/status", "VmSize").value_or(0.0) / 1024.0;
    consider(static_cast<double>(address_space.rlim_cur) / kMiB - virtual_mb, "RLIMIT_AS (ulimit -v)");
  }
  return limit;
}

}  // namespace facets
