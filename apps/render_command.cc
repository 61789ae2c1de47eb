#include "apps/render_command.h"

#include <exception>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "apps/stop_on_signal.h"
#include "io/output_folder.h"
#include "scenes/renderer.h"
#include "scenes/scene.h"

namespace facets {
namespace {

struct RenderArgs {
  std::string scene;
  std::string out;
  std::optional<int> seed;
  std::optional<double> noise;
  std::optional<int> supersampling;
};

// The scene into a temporary folder that replaces --out only when complete (as
// reconstruct's output, io/output_folder.h); a failure or SIGINT/SIGTERM leaves --out as
// it was. A folder holding files but none that a render writes is refused.
void RunRender(const RenderArgs& args) {
  const Scene scene = LoadScene(args.scene);
  RenderOptions options;
  options.seed = args.seed;
  options.noise_sigma = args.noise;
  options.supersampling = args.supersampling;
  options.progress = [](int i, int n, const std::string& name) {
    std::cout << "image " << i << "/" << n << " " << name << "\n" << std::flush;
  };
  CheckReplaceable(args.out, {"scene.json", "truth.json", "project.json"});
  for (const std::string& stale : RemoveStaleTemporaryFolders(args.out)) {
    std::cout << "removed " << stale << " (left by a run that was killed)\n";
  }
  OutputFolder output(args.out, OutputFolder::Start::kEmpty);
  StopOnSignal stop([&](const std::string& signal) {
    output.Abandon();
    std::cerr << "facets render: error: stopped by " << signal << "\nfacets render: " << output.out()
              << " is unchanged\n";
  });
  std::cout << "rendering scene '" << scene.name << "' from " << args.scene << " into " << args.out << "\n";
  try {
    const RenderSummary s = RenderSceneInto(scene, output.path(), options);
    stop.Finish([&] { output.Commit(); });
    std::cout << "done: " << s.images << " images, " << s.pixels << " pixels, " << s.triangles
              << " truth triangles, " << s.tie_points << " tie points, " << s.render_seconds << " s rendering, "
              << s.seconds << " s total\n";
  } catch (const std::exception& e) {
    stop.Finish([&] { output.Abandon(); });
    throw std::runtime_error(output.InFinalNames(e.what()) + "\nfacets render: " + output.out() + " is unchanged");
  }
}

}  // namespace

void AddRenderCommand(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* sub = app.add_subcommand(
      "render", "render a synthetic scene: images, COLMAP model, project file and truth");
  sub->add_option("scene", args->scene, "scene description (JSON)")->required();
  sub->add_option("--out", args->out, "output folder (replaced atomically)")->required();
  sub->add_option("--seed", args->seed, "random seed of noise and tie points (default: scene's)");
  sub->add_option("--noise", args->noise, "noise sigma in grey values (default: scene's)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--supersampling", args->supersampling,
                  "S x S sub-samples per pixel (default: scene's)")
      ->check(CLI::Range(1, 16));
  sub->callback([args] {
    try {
      RunRender(*args);
    } catch (const std::exception& e) {
      std::cerr << "facets render: error: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace facets
