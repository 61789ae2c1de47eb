// The output folder as a unit through the real `facets` binary on a small seed gable
// run (one level, two iterations, a 12 m x 12 m region: a few seconds): a failing run,
// SIGKILL and SIGINT at ten moments each, planted symbolic links and an export with a
// bad CRS into the run folder leave --out holding the complete previous output or the
// complete new one, never a mix, never a temporary file, and follow no link.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "io/folder_snapshot_for_testing.h"

extern char** environ;

namespace facets {
namespace {
namespace fs = std::filesystem;

std::vector<std::string> Names(const std::map<std::string, std::string>& files) {
  std::vector<std::string> names;
  for (const auto& [name, content] : files) names.push_back(name);
  return names;
}

// Siblings of `out` whose name starts with "<out name><infix>".
int Siblings(const fs::path& out, const std::string& infix) {
  int n = 0;
  for (const auto& entry : fs::directory_iterator(out.parent_path())) {
    n += entry.path().filename().string().rfind(out.filename().string() + infix, 0) == 0;
  }
  return n;
}

// Starts the facets CLI (argument words) with stdout and stderr into files; returns its pid.
pid_t Start(const std::vector<std::string>& args, const fs::path& log_stem) {
  std::vector<std::string> words = {FACETS_CLI};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, 1, (log_stem.string() + ".out").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&files, 2, (log_stem.string() + ".err").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  EXPECT_EQ(posix_spawn(&pid, FACETS_CLI, &files, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&files);
  return pid;
}

// Waits until the run `pid` has made its temporary folder beside `out` (it has started
// its work: the program is loaded and its signal handlers are in place).
void WaitForTheTemporaryFolder(const fs::path& out, pid_t pid) {
  const std::string infix = ".facets-tmp-";
  std::string tail = "-";
  tail += std::to_string(pid);
  tail += "-";
  for (int poll = 0; poll < 12000; ++poll) {
    for (const auto& entry : fs::directory_iterator(out.parent_path())) {
      const std::string name = entry.path().filename().string();
      if (name.rfind(out.filename().string() + infix, 0) == 0 && name.find(tail) != std::string::npos) return;
    }
    siginfo_t ended{};
    if (waitid(P_PID, static_cast<id_t>(pid), &ended, WEXITED | WNOHANG | WNOWAIT) == 0 && ended.si_pid == pid) {
      return;  // ended already (left to Wait)
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

int Wait(pid_t pid) {
  int status = 0;
  EXPECT_EQ(waitpid(pid, &status, 0), pid);
  return status;
}

// Runs the facets CLI to its end; the exit status (-1 when killed), stderr in *err.
int Facets(const std::vector<std::string>& args, const fs::path& log_stem, std::string* err = nullptr) {
  const int status = Wait(Start(args, log_stem));
  const std::string text = FileText(log_stem.string() + ".err");
  if (err != nullptr) *err = text;
  if (status != 0) std::cout << "facets " << args[0] << ": status " << status << "\n" << text;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class OutputFolderCli : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: ctest runs the cases of this suite in parallel processes.
    dir_ = new fs::path(fs::path(testing::TempDir()) / ("facets_output_folder_cli_" + std::to_string(getpid())));
    fs::remove_all(*dir_);
    fs::create_directories(*dir_);
    const std::string scene = std::string(FACETS_SOURCE_DIR) + "/scenes/data/seed_gable_parallel.json";
    ASSERT_EQ(Facets({"render", scene, "--out", (*dir_ / "scene").string()}, *dir_ / "render"), 0);
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    fs::remove_all(*dir_, ignored);
    delete dir_;
  }

  static std::vector<std::string> Reconstruct(const fs::path& out) {
    return {"reconstruct", "--colmap", (*dir_ / "scene" / "sparse").string(), "--images",
            (*dir_ / "scene" / "images").string(), "--levels", "1", "--max-iterations", "2",
            "--roi", "-6", "-6", "0", "6", "6", "9", "--out", out.string()};
  }

  static fs::path* dir_;
};
fs::path* OutputFolderCli::dir_ = nullptr;

// A complete reconstruct output: its file list, a report.json and the log's last line.
void ExpectComplete(const std::map<std::string, std::string>& files, const std::vector<std::string>& names) {
  EXPECT_EQ(Names(files), names);
  ASSERT_TRUE(files.count("report.json") && files.count("facets.log"));
  EXPECT_EQ(files.at("report.json").rfind("{", 0), 0u);
  EXPECT_NE(files.at("facets.log").find("\nsummary: "), std::string::npos);
}

TEST_F(OutputFolderCli, AFailingRunLeavesThePreviousOutputByteIdenticalAndALogBesideIt) {
  const fs::path out = *dir_ / "failing";
  ASSERT_EQ(Facets(Reconstruct(out), *dir_ / "failing_1"), 0);
  const auto first = FolderSnapshot(out);
  EXPECT_EQ(first.size(), 15u);
  std::vector<std::string> args = Reconstruct(out);
  args.insert(args.end(), {"--lambda", "inf"});
  std::string err;
  EXPECT_EQ(Facets(args, *dir_ / "failing_2", &err), 1);
  EXPECT_NE(err.find("surface.glb: sigma 0 is -nan"), std::string::npos) << err;
  EXPECT_NE(err.find(out.string() + " is unchanged (a previous output there stays whole); log: " + out.string() +
                     ".failed.log"),
            std::string::npos)
      << err;
  EXPECT_EQ(FolderSnapshot(out), first);
  const std::string failed_log = FileText(out.string() + ".failed.log");
  EXPECT_NE(failed_log.find("stage products: writing into"), std::string::npos) << failed_log;
  EXPECT_NE(failed_log.find("error: "), std::string::npos) << failed_log;
  EXPECT_EQ(Siblings(out, ".facets-"), 0);
  // Input that fails after the output folder was made: the same.
  args = Reconstruct(out);
  args[4] = (*dir_ / "no_images").string();
  EXPECT_EQ(Facets(args, *dir_ / "failing_3", &err), 1);
  EXPECT_NE(err.find("no_images"), std::string::npos) << err;
  EXPECT_EQ(FolderSnapshot(out), first);
  // A folder of other files is not replaced.
  fs::create_directories(*dir_ / "photos");
  std::ofstream(*dir_ / "photos" / "a.jpg") << "jpeg";
  EXPECT_EQ(Facets(Reconstruct(*dir_ / "photos"), *dir_ / "failing_4", &err), 1);
  EXPECT_NE(err.find("photos: holds files but no earlier run's output"), std::string::npos) << err;
  EXPECT_EQ(FolderSnapshot(*dir_ / "photos").size(), 1u);
  // A run that succeeds removes the failure log.
  ASSERT_EQ(Facets(Reconstruct(out), *dir_ / "failing_5"), 0);
  EXPECT_FALSE(fs::exists(out.string() + ".failed.log"));
}

// SIGKILL and SIGINT at ten moments each through a run (fractions of a complete run's
// working time, measured here from the moment its temporary folder appears): after each, --out holds the complete previous output or the
// complete new one; a SIGINT run says that it stopped; what SIGKILL left beside --out is
// removed by the next run.
TEST_F(OutputFolderCli, KillingARunAtAnyMomentLeavesTheOldOrTheNewOutputWhole) {
  const fs::path out = *dir_ / "killed";
  const pid_t first = Start(Reconstruct(out), *dir_ / "killed_first");
  WaitForTheTemporaryFolder(out, first);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(Wait(first), 0);
  const double run_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  auto previous = FolderSnapshot(out);
  const std::vector<std::string> complete = Names(previous);
  int unchanged = 0, replaced = 0, stopped_with_message = 0;
  for (const int signal_number : {SIGINT, SIGKILL}) {
    for (int moment = 0; moment < 10; ++moment) {
      const fs::path stem = *dir_ / ("killed_" + std::to_string(signal_number) + "_" + std::to_string(moment));
      const pid_t pid = Start(Reconstruct(out), stem);
      WaitForTheTemporaryFolder(out, pid);
      std::this_thread::sleep_for(std::chrono::duration<double>(run_seconds * (0.05 + 0.1 * moment)));
      kill(pid, signal_number);
      const int status = Wait(pid);
      const std::string err = FileText(stem.string() + ".err");
      const auto now = FolderSnapshot(out);
      if (now == previous) {
        ++unchanged;
      } else {
        ExpectComplete(now, complete);
        ++replaced;
      }
      for (const auto& [name, content] : now) {
        EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
        EXPECT_EQ(name.find(".facets-"), std::string::npos) << name;
      }
      if (signal_number == SIGINT && WIFEXITED(status) && WEXITSTATUS(status) == 130) {
        EXPECT_NE(err.find("error: stopped by SIGINT"), std::string::npos) << err;
        EXPECT_EQ(now, previous);
        EXPECT_EQ(Siblings(out, ".facets-tmp-"), 0);
        EXPECT_NE(FileText(out.string() + ".failed.log").find("error: stopped by SIGINT"), std::string::npos);
        ++stopped_with_message;
      } else if (signal_number == SIGINT) {
        EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status << "\n" << err;
      }
      std::cout << (signal_number == SIGKILL ? "SIGKILL" : "SIGINT") << " at "
                << static_cast<int>(100 * (0.05 + 0.1 * moment)) << " % of a run: status " << status << ", output "
                << (now == previous ? "unchanged" : "new and complete") << "\n";
      previous = now;
    }
  }
  std::cout << "20 kills (SIGINT first): " << unchanged << " left the previous output, " << replaced << " the new one; "
            << stopped_with_message << " SIGINT stops said so\n";
  EXPECT_GT(stopped_with_message, 0);
  const int stale = Siblings(out, ".facets-tmp-");
  std::string err;
  ASSERT_EQ(Facets(Reconstruct(out), *dir_ / "killed_last", &err), 0);
  ExpectComplete(FolderSnapshot(out), complete);
  EXPECT_EQ(Siblings(out, ".facets-tmp-"), 0);
  const std::string log = FileText(out / "facets.log");
  size_t removed = 0;
  for (size_t at = log.find("(left by a run that was killed)"); at != std::string::npos;
       at = log.find("(left by a run that was killed)", at + 1)) {
    ++removed;
  }
  EXPECT_EQ(removed, static_cast<size_t>(stale)) << log;
  std::cout << stale << " temporary folders left by SIGKILL, removed by the next run\n";
}

// Links planted in the output folder (at the products' names and at the fixed temporary
// names of earlier versions) and at the failure log's name are replaced, never followed.
TEST_F(OutputFolderCli, PlantedSymbolicLinksAreNeverFollowed) {
  const fs::path out = *dir_ / "planted";
  ASSERT_EQ(Facets(Reconstruct(out), *dir_ / "planted_1"), 0);
  const fs::path victim = *dir_ / "victim.txt";
  std::ofstream(victim) << "precious";
  for (const char* name : {"surface.ply", "report.json", "facets.log", "dsm.tif", "surface.ply.tmp",
                           "report.json.tmp", "facets.log.tmp", "dsm.tif.tmp", "preview.png.tmp"}) {
    fs::remove(out / name);
    fs::create_symlink(victim, out / name);
  }
  fs::create_symlink(victim, out.string() + ".failed.log");
  std::vector<std::string> failing = Reconstruct(out);
  failing.insert(failing.end(), {"--lambda", "inf"});
  EXPECT_EQ(Facets(failing, *dir_ / "planted_2"), 1);
  EXPECT_EQ(FileText(victim), "precious");
  EXPECT_FALSE(fs::is_symlink(out.string() + ".failed.log"));
  EXPECT_TRUE(fs::is_symlink(out / "surface.ply"));  // the failed run changed nothing
  ASSERT_EQ(Facets(Reconstruct(out), *dir_ / "planted_3"), 0);
  EXPECT_EQ(FileText(victim), "precious");
  for (const auto& entry : fs::directory_iterator(out)) EXPECT_FALSE(entry.is_symlink()) << entry.path();
  // Export into a folder with links at the products' names.
  const fs::path exported = *dir_ / "planted_export";
  fs::create_directories(exported);
  for (const char* name : {"surface.glb", "ortho.tif", "surface.glb.tmp"}) fs::create_symlink(victim, exported / name);
  ASSERT_EQ(Facets({"export", out.string(), "--out", exported.string()}, *dir_ / "planted_4"), 0);
  EXPECT_EQ(FileText(victim), "precious");
  EXPECT_FALSE(fs::is_symlink(exported / "surface.glb"));
  EXPECT_FALSE(fs::is_symlink(exported / "ortho.tif"));
}

// `facets export RUN --out RUN --crs BAD` fails and leaves RUN as it was, so later
// exports of it still work.
TEST_F(OutputFolderCli, ExportWithABadCrsLeavesTheRunFolderUnchanged) {
  const fs::path run = *dir_ / "export_run";
  ASSERT_EQ(Facets(Reconstruct(run), *dir_ / "export_1"), 0);
  const auto before = FolderSnapshot(run);
  std::string err;
  EXPECT_EQ(Facets({"export", run.string(), "--out", run.string(), "--crs", "EPSG:99999999"}, *dir_ / "export_2", &err),
            1);
  EXPECT_NE(err.find("unknown CRS 'EPSG:99999999'"), std::string::npos) << err;
  EXPECT_NE(err.find(run.string() + " is unchanged"), std::string::npos) << err;
  EXPECT_EQ(FolderSnapshot(run), before);
  EXPECT_EQ(Siblings(run, ".facets-"), 0);
  ASSERT_EQ(Facets({"export", run.string(), "--out", (*dir_ / "export_again").string()}, *dir_ / "export_3"), 0);
  EXPECT_EQ(FileText(*dir_ / "export_again" / "surface.ply"), before.at("surface.ply"));
  // A good export into the run folder replaces the products and keeps the rest.
  ASSERT_EQ(Facets({"export", run.string(), "--out", run.string(), "--formats", "glb"}, *dir_ / "export_4"), 0);
  EXPECT_EQ(Names(FolderSnapshot(run)), Names(before));
  EXPECT_EQ(FolderSnapshot(run).at("report.json"), before.at("report.json"));
}

}  // namespace
}  // namespace facets
