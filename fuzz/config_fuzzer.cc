// The --config file of `facets reconstruct` (CLI11's INI reader over the command's
// options, apps/reconstruct_options), set up as apps/facets_main.cc does: the option on
// the top-level app, unknown keys are errors. A CLI::ParseError is the message for bad
// input. A file that parses must set the options without error, and the settings.ini
// written from those options must parse again (a run's settings.ini is re-readable).
#include <CLI/CLI.hpp>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "apps/reconstruct_options.h"
#include "fuzz/fuzz_input_file.h"

namespace {

// Parses `facets reconstruct --config PATH` into *line; false on a CLI::ParseError.
bool ParseConfig(const std::string& path, facets::ReconstructCommandLine* line, std::string* settings) {
  CLI::App app{"facets"};
  app.set_config("--config");
  app.allow_config_extras(CLI::config_extras_mode::error);
  CLI::App* sub = app.add_subcommand("reconstruct");
  sub->fallthrough();
  facets::BindReconstructOptions(sub, line);
  const char* argv[] = {"facets", "reconstruct", "--config", path.c_str()};
  try {
    app.parse(4, argv);
  } catch (const CLI::ParseError&) {
    return false;
  }
  facets::ApplySceneAndGivenOptions(line->app.scene, line);
  *settings = facets::SettingsFile(*sub);
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string settings;
  {
    const facets::FuzzInputFile file(data, size);
    facets::ReconstructCommandLine line;
    if (!ParseConfig(file.path(), &line, &settings)) return 0;
  }
  const facets::FuzzInputFile written(reinterpret_cast<const uint8_t*>(settings.data()), settings.size());
  facets::ReconstructCommandLine again;
  std::string settings_again;
  if (!ParseConfig(written.path(), &again, &settings_again) || settings_again != settings) {
    fprintf(stderr, "settings.ini does not read back:\n%s\n", settings.c_str());
    __builtin_trap();
  }
  return 0;
}
