#include "io/output_folder.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "io/atomic_file.h"

namespace facets {
namespace {

namespace fs = std::filesystem;

// The final folder: a trailing "/" dropped; a symbolic link given as --out is the user's
// own choice and stands for the folder it names.
fs::path Resolve(const std::string& out) {
  fs::path path(out);
  if (path.filename().empty()) path = path.parent_path();
  if (fs::is_symlink(fs::symlink_status(path))) {
    std::error_code ec;
    const fs::path target = fs::canonical(path, ec);
    if (ec) throw std::runtime_error(out + ": a symbolic link to nothing (" + ec.message() + ")");
    return target;
  }
  return path;
}

// This host's name as it appears in temporary folder names ("-" and odd characters as
// "_", so that the name splits at its last two "-").
std::string HostTag() {
  char name[256] = {};
  if (gethostname(name, sizeof(name) - 1) != 0) return "host";
  std::string tag;
  for (const char* c = name; *c != '\0'; ++c) tag += std::isalnum(static_cast<unsigned char>(*c)) || *c == '.' ? *c : '_';
  return tag.empty() ? "host" : tag;
}

std::string TemporaryPrefix(const fs::path& out) { return out.filename().string() + ".facets-tmp-"; }

// Makes a new folder "<out><infix><host>-<pid>-XXXXXX" (mkdir: never an existing name).
fs::path MakeUniqueFolder(const fs::path& out, const std::string& infix) {
  const std::string stem = out.string() + infix + HostTag() + "-" + std::to_string(getpid()) + "-";
  for (int attempt = 0; attempt < 100; ++attempt) {
    const fs::path folder = stem + RandomNameSuffix(6);
    if (::mkdir(folder.c_str(), 0777) == 0) return folder;
    if (errno != EEXIST) {
      throw std::runtime_error(out.string() + ": cannot make a temporary folder beside it: " + std::strerror(errno));
    }
  }
  throw std::runtime_error(out.string() + ": cannot make a temporary folder beside it: 100 names taken");
}

// The files of `from` into `to` as hard links (a copy where a link is refused),
// symbolic links as links (never followed), sub-folders alike.
void CarryOver(const fs::path& from, const fs::path& to) {
  for (const fs::directory_entry& entry : fs::directory_iterator(from)) {
    const fs::path target = to / entry.path().filename();
    const fs::file_status status = entry.symlink_status();
    if (fs::is_symlink(status)) {
      fs::copy_symlink(entry.path(), target);
    } else if (fs::is_directory(status)) {
      fs::create_directory(target, entry.path());
      CarryOver(entry.path(), target);
    } else if (fs::is_regular_file(status)) {
      std::error_code refused;
      fs::create_hard_link(entry.path(), target, refused);
      if (refused) fs::copy_file(entry.path(), target);
    }
  }
}

void RemoveFolderQuietly(const fs::path& folder) {
  // A writer still running in another thread may add a file while the folder goes.
  for (int attempt = 0; attempt < 5; ++attempt) {
    std::error_code ec;
    fs::remove_all(folder, ec);
    if (!ec) return;
  }
}

}  // namespace

OutputFolder::OutputFolder(const std::string& out, Start start) {
  const fs::path final_path = Resolve(out);
  out_ = final_path.string();
  const fs::file_status status = fs::status(final_path);
  if (fs::exists(status) && !fs::is_directory(status)) throw std::runtime_error(out_ + ": exists and is not a folder");
  try {
    if (final_path.has_parent_path()) fs::create_directories(final_path.parent_path());
    const fs::path temporary = MakeUniqueFolder(final_path, ".facets-tmp-");
    temporary_ = temporary.string();
    if (fs::exists(status)) {
      if (start == Start::kPreviousFiles) CarryOver(final_path, temporary);
      fs::permissions(temporary, status.permissions());
    }
  } catch (const fs::filesystem_error& e) {
    if (!temporary_.empty()) RemoveFolderQuietly(temporary_);
    throw std::runtime_error(out_ + ": cannot prepare the new output beside it: " + e.what());
  }
}

OutputFolder::~OutputFolder() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!committed_ && !abandoned_) RemoveFolderQuietly(temporary_);
}

std::string OutputFolder::InFinalNames(std::string message) const {
  for (size_t at = message.find(temporary_); at != std::string::npos; at = message.find(temporary_, at + out_.size())) {
    message.replace(at, temporary_.size(), out_);
  }
  return message;
}

void OutputFolder::Swap() {
  if (!fs::exists(fs::symlink_status(out_))) {
    if (::rename(temporary_.c_str(), out_.c_str()) != 0) {
      throw std::runtime_error(out_ + ": cannot move the new output into place: " + std::strerror(errno));
    }
    return;
  }
  if (::renameat2(AT_FDCWD, temporary_.c_str(), AT_FDCWD, out_.c_str(), RENAME_EXCHANGE) == 0) return;
  if (errno != EINVAL && errno != ENOSYS && errno != ENOTSUP) {
    throw std::runtime_error(out_ + ": cannot swap in the new output: " + std::strerror(errno));
  }
  // No exchange on this file system: the previous output aside under a unique name
  // (never removed automatically before the new one is in place), then back on failure.
  const fs::path aside = MakeUniqueFolder(out_, ".facets-previous-");
  if (::rename(out_.c_str(), aside.c_str()) != 0) {
    const int error = errno;
    ::rmdir(aside.c_str());
    throw std::runtime_error(out_ + ": cannot move the previous output aside: " + std::strerror(error));
  }
  if (::rename(temporary_.c_str(), out_.c_str()) != 0) {
    const int error = errno;
    ::rename(aside.c_str(), out_.c_str());
    throw std::runtime_error(out_ + ": cannot move the new output into place: " + std::strerror(error));
  }
  temporary_ = aside.string();
}

void OutputFolder::Commit() {
  std::string previous;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (abandoned_) throw std::runtime_error(out_ + ": the run was stopped; the new output is gone");
    Swap();
    committed_ = true;
    previous = temporary_;
  }
  RemoveFolderQuietly(previous);
}

bool OutputFolder::Abandon() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (committed_) return true;
  if (!abandoned_) RemoveFolderQuietly(temporary_);
  abandoned_ = true;
  return false;
}

std::vector<std::string> RemoveStaleTemporaryFolders(const std::string& out) {
  const fs::path final_path = Resolve(out);
  const fs::path parent = final_path.has_parent_path() ? final_path.parent_path() : fs::path(".");
  const std::string prefix = TemporaryPrefix(final_path) + HostTag() + "-";
  std::vector<std::string> removed;
  std::error_code ec;
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    // "<pid>-XXXXXX" after the prefix.
    const std::string rest = name.substr(prefix.size());
    const size_t dash = rest.find('-');
    if (dash == 0 || dash == std::string::npos || rest.size() != dash + 7 ||
        rest.find_first_not_of("0123456789") != dash) {
      continue;
    }
    struct stat info {};
    if (::lstat(it->path().c_str(), &info) != 0 || !S_ISDIR(info.st_mode) || info.st_uid != ::getuid()) continue;
    const long pid = std::stol(rest.substr(0, dash));
    if (pid <= 0 || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    RemoveFolderQuietly(it->path());
    removed.push_back(it->path().string());
  }
  return removed;
}

void CheckReplaceable(const std::string& out, const std::vector<std::string>& markers) {
  const fs::path final_path = Resolve(out);
  const fs::file_status status = fs::status(final_path);
  if (!fs::exists(status)) return;
  if (!fs::is_directory(status)) throw std::runtime_error(final_path.string() + ": exists and is not a folder");
  if (fs::is_empty(final_path)) return;
  std::string names;
  for (const std::string& marker : markers) {
    if (fs::exists(fs::symlink_status(final_path / marker))) return;
    names += (names.empty() ? "" : ", ") + marker;
  }
  throw std::runtime_error(final_path.string() + ": holds files but no earlier run's output (none of " + names +
                           "); a run replaces its output folder as a whole: give a new or empty folder");
}

}  // namespace facets
