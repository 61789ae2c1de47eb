// The output folder as a unit (io/output_folder.h) and the exclusive temporaries of
// io/atomic_file.h, on real files: a commit swaps the whole folder, an uncommitted or
// abandoned one leaves the previous output byte for byte, carried-over files are never
// written through, symbolic links are replaced and never followed, and the temporary
// folder of a process that died without cleaning up is found and removed.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "io/atomic_file.h"
#include "io/folder_snapshot_for_testing.h"
#include "io/output_folder.h"

namespace facets {
namespace {
namespace fs = std::filesystem;

// Entries of `parent` whose name starts with `prefix`.
int EntriesStartingWith(const fs::path& parent, const std::string& prefix) {
  int n = 0;
  for (const auto& entry : fs::directory_iterator(parent)) n += entry.path().filename().string().rfind(prefix, 0) == 0;
  return n;
}

fs::path FreshDir(const std::string& name) {
  const fs::path dir = fs::path(testing::TempDir()) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(OutputFolder, CommitReplacesTheWholeFolderAndAnUncommittedOneLeavesItAsItWas) {
  const fs::path dir = FreshDir("facets_output_folder_commit");
  const fs::path out = dir / "out";
  {
    OutputFolder first(out.string(), OutputFolder::Start::kEmpty);
    EXPECT_FALSE(fs::exists(out));
    WriteFileAtomically((fs::path(first.path()) / "a.txt").string(), "first a");
    WriteFileAtomically((fs::path(first.path()) / "old_only.txt").string(), "old");
    first.Commit();
  }
  const auto previous = FolderSnapshot(out);
  ASSERT_EQ(previous.size(), 2u);
  {
    OutputFolder failed(out.string(), OutputFolder::Start::kEmpty);
    WriteFileAtomically((fs::path(failed.path()) / "a.txt").string(), "half");
  }  // no commit: the error path
  EXPECT_EQ(FolderSnapshot(out), previous);
  {
    OutputFolder stopped(out.string(), OutputFolder::Start::kEmpty);
    WriteFileAtomically((fs::path(stopped.path()) / "a.txt").string(), "stopped");
    EXPECT_FALSE(stopped.Abandon());
    EXPECT_THROW(stopped.Commit(), std::runtime_error);
  }
  EXPECT_EQ(FolderSnapshot(out), previous);
  {
    OutputFolder second(out.string(), OutputFolder::Start::kEmpty);
    WriteFileAtomically((fs::path(second.path()) / "a.txt").string(), "second a");
    second.Commit();
    EXPECT_TRUE(second.Abandon());  // too late: the output is in place
  }
  EXPECT_EQ(FolderSnapshot(out), (std::map<std::string, std::string>{{"a.txt", "second a"}}));
  EXPECT_EQ(EntriesStartingWith(dir, "out."), 0);  // no temporary or previous folder left
}

TEST(OutputFolder, PreviousFilesAreCarriedOverAndNeverWrittenThrough) {
  const fs::path dir = FreshDir("facets_output_folder_carry");
  const fs::path out = dir / "run";
  fs::create_directories(out / "levels");
  std::ofstream(out / "report.json") << "report";
  std::ofstream(out / "surface.glb") << "old glb";
  std::ofstream(out / "levels" / "level_0.ply") << "level";
  std::ofstream(dir / "victim.txt") << "precious";
  fs::create_symlink(dir / "victim.txt", out / "surface.wrl");
  const auto before = FolderSnapshot(out);
  {
    OutputFolder update(out.string(), OutputFolder::Start::kPreviousFiles);
    EXPECT_EQ(FolderSnapshot(update.path()), before);
    WriteFileAtomically((fs::path(update.path()) / "surface.glb").string(), "new glb");
    WriteFileAtomically((fs::path(update.path()) / "surface.wrl").string(), "new wrl");
    EXPECT_EQ(FolderSnapshot(out), before);  // the hard links were replaced, not written into
  }
  EXPECT_EQ(FolderSnapshot(out), before);
  {
    OutputFolder update(out.string(), OutputFolder::Start::kPreviousFiles);
    WriteFileAtomically((fs::path(update.path()) / "surface.glb").string(), "new glb");
    WriteFileAtomically((fs::path(update.path()) / "surface.wrl").string(), "new wrl");
    update.Commit();
  }
  auto after = before;
  after["surface.glb"] = "new glb";
  after["surface.wrl"] = "new wrl";
  EXPECT_EQ(FolderSnapshot(out), after);
  EXPECT_FALSE(fs::is_symlink(out / "surface.wrl"));
  EXPECT_EQ(FileText(dir / "victim.txt"), "precious");
}

TEST(OutputFolder, WritesReplaceSymbolicLinksAndNeverFollowThem) {
  const fs::path dir = FreshDir("facets_output_folder_links");
  std::ofstream(dir / "victim.txt") << "precious";
  fs::create_symlink(dir / "victim.txt", dir / "report.json");
  fs::create_symlink(dir / "victim.txt", dir / "report.json.tmp");
  WriteFileAtomically((dir / "report.json").string(), "new");
  EXPECT_EQ(FileText(dir / "victim.txt"), "precious");
  EXPECT_FALSE(fs::is_symlink(dir / "report.json"));
  EXPECT_EQ(FileText(dir / "report.json"), "new");
  const std::string tmp = CreateTemporaryBeside((dir / "a.tif").string());
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(tmp)));
  EXPECT_NE(fs::path(tmp).filename().string().find(".a.tif.facets-"), std::string::npos) << tmp;
  CommitTemporary(tmp, (dir / "a.tif").string());
  // Only the planted link and the three real files: no temporary left.
  EXPECT_EQ(FolderSnapshot(dir).size(), 4u);
}

TEST(OutputFolder, ReplacesOnlyEmptyFoldersOrEarlierOutputs) {
  const fs::path dir = FreshDir("facets_output_folder_replaceable");
  const std::vector<std::string> markers = {"facets.log", "report.json"};
  EXPECT_NO_THROW(CheckReplaceable((dir / "new").string(), markers));
  fs::create_directories(dir / "empty");
  EXPECT_NO_THROW(CheckReplaceable((dir / "empty").string(), markers));
  fs::create_directories(dir / "photos");
  std::ofstream(dir / "photos" / "a.jpg") << "jpeg";
  try {
    CheckReplaceable((dir / "photos").string(), markers);
    ADD_FAILURE() << "a folder of other files was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("photos: holds files but no earlier run's output (none of facets.log, "
                                         "report.json)"),
              std::string::npos)
        << e.what();
  }
  std::ofstream(dir / "photos" / "facets.log") << "log";
  EXPECT_NO_THROW(CheckReplaceable((dir / "photos").string(), markers));
  std::ofstream(dir / "file") << "x";
  EXPECT_THROW(CheckReplaceable((dir / "file").string(), markers), std::runtime_error);
  EXPECT_THROW(OutputFolder((dir / "file").string(), OutputFolder::Start::kEmpty), std::runtime_error);
}

// A child process makes its temporary folder and dies without cleaning up (what SIGKILL
// leaves); the next run removes that folder, and never a symbolic link of such a name.
TEST(OutputFolder, RemovesTheTemporaryFoldersOfDeadProcessesOnly) {
  const fs::path dir = FreshDir("facets_output_folder_stale");
  const fs::path out = dir / "out";
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    OutputFolder dying(out.string(), OutputFolder::Start::kEmpty);
    WriteFileAtomically((fs::path(dying.path()) / "surface.ply").string(), "partial");
    _exit(0);  // no destructor: the folder stays
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_EQ(EntriesStartingWith(dir, "out.facets-tmp-"), 1);
  std::string stale_name;
  for (const auto& entry : fs::directory_iterator(dir)) stale_name = entry.path().filename().string();
  fs::create_directories(dir / "elsewhere");
  std::ofstream(dir / "elsewhere" / "keep.txt") << "keep";
  // A link named like a dead process's folder, pointing elsewhere: not a folder of ours.
  std::string link_name = stale_name;
  link_name.back() = link_name.back() == 'z' ? 'y' : 'z';
  fs::create_directory_symlink(dir / "elsewhere", dir / link_name);
  OutputFolder mine(out.string(), OutputFolder::Start::kEmpty);  // alive: must stay
  const std::vector<std::string> removed = RemoveStaleTemporaryFolders(out.string());
  ASSERT_EQ(removed.size(), 1u);
  EXPECT_EQ(fs::path(removed[0]).filename().string(), stale_name);
  EXPECT_TRUE(fs::is_directory(mine.path()));
  EXPECT_TRUE(fs::is_symlink(dir / link_name));
  EXPECT_EQ(FileText(dir / "elsewhere" / "keep.txt"), "keep");
}

}  // namespace
}  // namespace facets
