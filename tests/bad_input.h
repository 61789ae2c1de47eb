// The bad-input suite (tests/bad_input_*_test.cc): the facets binary run on one bad
// input at a time, and what every case asserts about it: a non-zero exit, a message on
// stderr naming the file and the problem, and no products in the output folder.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

namespace facets::bad_input {

namespace fs = std::filesystem;

inline std::string FileText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline void WriteText(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

// A fresh folder for the running test, below the test's temporary folder.
inline fs::path CaseFolder() {
  const testing::TestInfo* test = testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(testing::TempDir()) / "facets_bad_input" /
                       (std::string(test->test_suite_name()) + "." + test->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// The files below `dir`; `dir` itself when it is a file (an output file); none when it
// does not exist.
inline std::vector<std::string> FilesBelow(const fs::path& dir) {
  std::vector<std::string> files;
  if (fs::exists(dir) && !fs::is_directory(dir)) files.push_back(dir.string());
  if (!fs::is_directory(dir)) return files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!entry.is_directory()) files.push_back(entry.path().string());
  }
  return files;
}

struct Outcome {
  int status = -1;  // exit status; -1 when the process did not exit (a signal: a crash)
  std::string err;  // stderr
};

// Runs the facets CLI with `args` (stderr and stdout into files per process).
inline Outcome RunFacets(const std::string& args) {
  const std::string stem = testing::TempDir() + "/facets_bad_input_" + std::to_string(getpid());
  const std::string command =
      std::string(FACETS_CLI) + " " + args + " > " + stem + ".out 2> " + stem + ".err";
  const int status = std::system(command.c_str());
  Outcome outcome;
  outcome.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  outcome.err = FileText(stem + ".err");
  return outcome;
}

// One bad-input case: facets `args` must exit non-zero (not by a signal), its stderr must
// hold every one of `needles` (the file's name and words of the problem), and `out`
// must hold no products afterwards.
inline void ExpectRefused(const std::string& args, const std::vector<std::string>& needles,
                          const fs::path& out) {
  const Outcome outcome = RunFacets(args);
  std::cout << "facets " << args << "\n  -> status " << outcome.status << ": " << outcome.err;
  EXPECT_GT(outcome.status, 0) << args;
  for (const std::string& needle : needles) {
    EXPECT_NE(outcome.err.find(needle), std::string::npos)
        << "'" << needle << "' not in the message of facets " << args << ":\n" << outcome.err;
  }
  EXPECT_EQ(outcome.err.find("bad_alloc"), std::string::npos) << outcome.err;
  const std::vector<std::string> products = FilesBelow(out);
  EXPECT_TRUE(products.empty()) << args << ": " << products.size() << " files in " << out
                                << (products.empty() ? "" : ", e.g. " + products.front());
}

}  // namespace facets::bad_input
