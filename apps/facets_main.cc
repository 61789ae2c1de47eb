#include <CLI/CLI.hpp>
#include <iostream>

#include "apps/creases_command.h"
#include "apps/evaluate_command.h"
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
                                 "each run writes); options on the command line win");
  app.allow_config_extras(CLI::config_extras_mode::error);
  app.add_subcommand("version", "print the version")->callback([] { std::cout << "facets 0.1\n"; });
  facets::AddRenderCommand(app);
  facets::AddEvaluateCommand(app);
  facets::AddReconstructCommand(app);
  facets::AddExportCommand(app);
  facets::AddCreasesCommand(app);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
