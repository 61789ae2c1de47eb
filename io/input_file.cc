#include "io/input_file.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <numeric>
#include <stdexcept>
#include <system_error>

namespace facets {

namespace fs = std::filesystem;

void CheckInputFile(const std::string& path, const std::string& what, bool allow_empty) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) throw std::runtime_error(path + ": " + what + " not found");
  if (fs::is_directory(status)) {
    throw std::runtime_error(path + ": is a folder, not a " + what);
  }
  if (!allow_empty && fs::is_regular_file(status) && fs::file_size(path, ec) == 0 && !ec) {
    throw std::runtime_error(path + ": " + what + " is empty (0 bytes)");
  }
}

std::ifstream OpenInputFile(const std::string& path, const std::string& what, bool allow_empty) {
  CheckInputFile(path, what, allow_empty);
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw std::runtime_error(path + ": cannot open " + what + ": " + std::strerror(errno));
  }
  return in;
}

size_t EditDistance(std::string_view a, std::string_view b) {
  // One row of the dynamic programme: row[j] = distance of a[0, i) to b[0, j).
  std::vector<size_t> row(b.size() + 1);
  std::iota(row.begin(), row.end(), size_t{0});
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string NearestName(std::string_view key, const std::vector<std::string>& candidates) {
  std::string nearest;
  size_t best = SIZE_MAX;
  for (const std::string& candidate : candidates) {
    const size_t distance = EditDistance(key, candidate);
    if (distance < best) {
      best = distance;
      nearest = candidate;
    }
  }
  return nearest;
}

std::string UnknownKeyMessage(std::string_view key, const std::vector<std::string>& known) {
  std::string message = "unknown key '" + std::string(key) + "'";
  const std::string nearest = NearestName(key, known);
  if (!nearest.empty()) message += " (nearest known key: '" + nearest + "')";
  return message;
}

}  // namespace facets
