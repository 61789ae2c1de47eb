#include <CLI/CLI.hpp>
#include <iostream>
#include <string>
#include <vector>

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
    // CLI11 names the key ("INI was not able to parse reconstruct.levles"); add the file.
    const std::vector<std::string> files = app.get_config_ptr()->results();
    std::string message = e.what();
    const std::string unknown = "INI was not able to parse ";
    if (message.rfind(unknown, 0) == 0) message = "unknown option '" + message.substr(unknown.size()) + "'";
    std::cerr << "facets: config file " << (files.empty() ? std::string("?") : files.front()) << ": " << message
              << "\n";
    return e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return 0;
}
