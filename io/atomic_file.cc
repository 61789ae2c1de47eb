#include "io/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <system_error>

namespace facets {
namespace {

// Opens a new file with a unique name beside path for writing; returns the descriptor
// and the name in *tmp. The mode 0666 is narrowed by the umask like any new file.
int OpenUniqueTemporary(const std::string& path, std::string* tmp) {
  const std::filesystem::path target(path);
  std::string stem = ".";
  stem += target.filename().string();
  stem += ".facets-";
  for (int attempt = 0; attempt < 100; ++attempt) {
    *tmp = (target.parent_path() / (stem + RandomNameSuffix(6))).string();
    const int fd = ::open(tmp->c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd >= 0) return fd;
    if (errno != EEXIST) {
      throw std::runtime_error(path + ": cannot create a temporary file beside it: " + std::strerror(errno));
    }
  }
  throw std::runtime_error(path + ": cannot create a temporary file beside it: 100 names taken");
}

}  // namespace

std::string RandomNameSuffix(int length) {
  static std::atomic<unsigned long long> counter{0};
  static const unsigned long long seed = std::random_device{}();
  std::mt19937_64 random(seed ^ (++counter * 0x9E3779B97F4A7C15ULL) ^ static_cast<unsigned long long>(getpid()));
  static const char kAlphabet[] = "abcdefghijklmnopqrstuvwxyz0123456789";
  std::string name;
  for (int i = 0; i < length; ++i) name += kAlphabet[random() % (sizeof(kAlphabet) - 1)];
  return name;
}

void WriteFileAtomically(const std::string& path, std::string_view content) {
  std::string tmp;
  const int fd = OpenUniqueTemporary(path, &tmp);
  const char* data = content.data();
  size_t left = content.size();
  int error = 0;
  while (left > 0) {
    const ssize_t written = ::write(fd, data, left);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) {
      error = written < 0 ? errno : ENOSPC;
      break;
    }
    data += written;
    left -= static_cast<size_t>(written);
  }
  if (::close(fd) != 0 && error == 0) error = errno;
  if (error != 0) {
    RemoveTemporary(tmp);
    throw std::runtime_error(path + ": write failed: " + std::strerror(error));
  }
  CommitTemporary(tmp, path);
}

std::string CreateTemporaryBeside(const std::string& path) {
  std::string tmp;
  ::close(OpenUniqueTemporary(path, &tmp));
  return tmp;
}

void CommitTemporary(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    RemoveTemporary(tmp);
    throw std::runtime_error(path + ": cannot rename the temporary file: " + ec.message());
  }
}

void RemoveTemporary(const std::string& tmp) {
  std::error_code ignored;
  std::filesystem::remove(tmp, ignored);
}

}  // namespace facets
