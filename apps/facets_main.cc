#include <CLI/CLI.hpp>
#include <iostream>
#include <string>
#include <vector>

#include "apps/creases_command.h"
#include "apps/evaluate_command.h"
#include "apps/option_binder.h"
#include "apps/export_command.h"
#include "apps/reconstruct_command.h"
#include "apps/render_command.h"

int main(int argc, char** argv) {
  CLI::App app{"Facets: multi-image least-squares surface reconstruction"};
  app.require_subcommand(1);
  // Config files belong to the top-level app: CLI11 does not read a subcommand's own
  // (a `--config` set on `reconstruct` was silently ignored). Options sit in a section
  // named after the subcommand, as the settings.ini a reconstruction writes; unknown
  // keys are errors, not silently dropped; options on the command line win.
  app.set_config("--config", "", "config file: `option = value` lines in a [reconstruct] section (the settings.ini "
                                 "each run writes); options on the command line win")
      ->check(CLI::ExistingFile);  // a missing file or a folder named as such
  app.allow_config_extras(CLI::config_extras_mode::error);
  // Before the subcommands: they inherit it (`facets reconstruct --help-all` lists the
  // expert options too).
  app.set_help_all_flag("--help-all", "print the help with every option and exit");
  app.add_subcommand("version", "print the version")->callback([] { std::cout << "facets 0.1\n"; });
  facets::AddRenderCommand(app);
  facets::AddEvaluateCommand(app);
  facets::AddReconstructCommand(app);
  facets::AddExportCommand(app);
  facets::AddCreasesCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ConfigError& e) {
    const std::vector<std::string> files = app.get_config_ptr()->results();
    std::cerr << "facets: " << facets::ConfigErrorMessage(app, files.empty() ? "?" : files.front(), e.what())
              << "\n";
    return e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    const std::string config_value = facets::ConfigValueErrorMessage(app, e);
    if (!config_value.empty()) {
      std::cerr << "facets: " << config_value << "\n";
      return e.get_exit_code();
    }
    return app.exit(e);
  }
  return 0;
}
