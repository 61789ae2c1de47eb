#include <CLI/CLI.hpp>
#include <iostream>

#include "apps/evaluate_command.h"
#include "apps/export_command.h"
#include "apps/reconstruct_command.h"
#include "apps/render_command.h"

int main(int argc, char** argv) {
  CLI::App app{"Facets: multi-image least-squares surface reconstruction"};
  app.require_subcommand(1);
  app.add_subcommand("version", "print the version")->callback([] { std::cout << "facets 0.1\n"; });
  facets::AddRenderCommand(app);
  facets::AddEvaluateCommand(app);
  facets::AddReconstructCommand(app);
  facets::AddExportCommand(app);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
