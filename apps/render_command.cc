#include "apps/render_command.h"

#include <exception>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

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

void RunRender(const RenderArgs& args) {
  const Scene scene = LoadScene(args.scene);
  RenderOptions options;
  options.seed = args.seed;
  options.noise_sigma = args.noise;
  options.supersampling = args.supersampling;
  options.progress = [](int i, int n, const std::string& name) {
    std::cout << "image " << i << "/" << n << " " << name << "\n" << std::flush;
  };
  std::cout << "rendering scene '" << scene.name << "' from " << args.scene << " into "
            << args.out << "\n";
  const RenderSummary s = RenderScene(scene, args.out, options);
  std::cout << "done: " << s.images << " images, " << s.pixels << " pixels, " << s.triangles
            << " truth triangles, " << s.tie_points << " tie points, " << s.render_seconds
            << " s rendering, " << s.seconds << " s total\n";
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
