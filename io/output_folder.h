// A command's output folder written as a unit: everything goes into a fresh temporary
// folder beside the final one, which takes the final name only when everything is
// written. The previous output stays whole until then, and is swapped out in one step
// (renameat2 RENAME_EXCHANGE; where the file system lacks it, renamed aside and back on
// failure). So a failed, interrupted or killed run leaves the complete previous output
// or the complete new one, never a mix.
//
// The temporary folder is "<out>.facets-tmp-<host>-<pid>-XXXXXX": created with mkdir (an
// existing name, a symbolic link too, is never used) and a random suffix. A run killed
// with SIGKILL can leave only that folder; a later run with the same --out removes the
// ones whose process is gone (RemoveStaleTemporaryFolders).
#pragma once

#include <mutex>
#include <string>
#include <vector>

namespace facets {

class OutputFolder {
 public:
  enum class Start {
    kEmpty,           // the new output replaces the previous folder as a whole
    kPreviousFiles,   // the new output starts with the previous folder's files (hard
                      // links: writers must replace files by rename, io/atomic_file.h)
  };

  // `out` is the final folder; when it is a symbolic link, the folder it names. Throws
  // std::runtime_error naming `out` when it exists and is not a folder, or the temporary
  // folder cannot be made beside it.
  OutputFolder(const std::string& out, Start start);
  ~OutputFolder();  // removes the temporary folder unless committed
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  // Where the run writes (the temporary folder).
  const std::string& path() const { return temporary_; }
  // The final folder.
  const std::string& out() const { return out_; }
  // `message` (a writer's error naming a file it wrote) with the temporary folder's name
  // replaced by the final one, as the user knows it.
  std::string InFinalNames(std::string message) const;

  // The temporary folder takes the final name; the previous output is removed after.
  // Throws std::runtime_error naming the folder when the rename fails (the previous
  // output is then in place).
  void Commit();
  // Removes the temporary folder unless Commit has already swapped it in (then returns
  // true). Safe to call from another thread while the run writes (a signal watcher).
  bool Abandon();

 private:
  void Swap();

  std::string out_;
  std::string temporary_;
  std::mutex mutex_;
  bool committed_ = false;
  bool abandoned_ = false;
};

// Removes the temporary folders beside `out` ("<out>.facets-tmp-<host>-<pid>-XXXXXX",
// real folders owned by this user) of runs on this host whose process no longer exists:
// what SIGKILL left. Returns their names. A folder whose process id was reused since is
// left (it cannot be told from a running run).
std::vector<std::string> RemoveStaleTemporaryFolders(const std::string& out);

// Throws std::runtime_error naming `out` when it exists and is neither an empty folder
// nor a folder holding one of `markers` (file names a previous run wrote): a folder
// replaced as a whole must not be a user's folder of other files.
void CheckReplaceable(const std::string& out, const std::vector<std::string>& markers);

}  // namespace facets
