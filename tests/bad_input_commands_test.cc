// Bad input to the mesh readers (PLY, OBJ) and to the subcommands other than
// reconstruct: creases, export, evaluate, render. tests/bad_input.h says what every
// case asserts; tests/bad_input_readers_test.cc has reconstruct's readers.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <map>
#include <string>

#include "io/folder_snapshot_for_testing.h"
#include "io/ply_io.h"
#include "tests/bad_input.h"

namespace facets::bad_input {
namespace {

// A binary little-endian PLY with `vertices` double x y z and `faces` uchar/int lists as
// claimed in the header, followed by `body` (whatever bytes the case needs).
std::string BinaryPly(const std::string& vertices, const std::string& faces, const std::string& body,
                      const std::string& list_count_type = "uchar") {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + vertices +
         "\nproperty double x\nproperty double y\nproperty double z\nelement face " + faces + "\nproperty list " +
         list_count_type + " int vertex_indices\nend_header\n" + body;
}

// One triangle: three vertices at the corners of the unit square's lower half.
MeshData Triangle() {
  MeshData mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.faces = {{0, 1, 2}};
  return mesh;
}

class BadMesh : public testing::Test {
 protected:
  void SetUp() override { dir_ = CaseFolder(); }
  // `facets creases` on `tin`: its first step reads the TIN.
  std::string Creases(const fs::path& tin) const {
    return "creases " + tin.string() + " --edge 1 --out " + Out().string();
  }
  fs::path Out() const { return dir_ / "out.ply"; }
  fs::path dir_;
};

TEST_F(BadMesh, PlyHeaderCountsAreCheckedAgainstTheFileSize) {
  const fs::path ply = dir_ / "huge.ply";
  WriteText(ply, BinaryPly("100000000", "0", std::string(40, '\0')));
  ASSERT_LT(fs::file_size(ply), 260u);
  ExpectRefused(Creases(ply), {"huge.ply", "100000000 vertex", "need at least 2400000000 bytes", "only 40 bytes"},
                Out());
  WriteText(ply, "ply\nformat ascii 1.0\nelement vertex 100000000\nproperty float x\nproperty float y\n"
                 "property float z\nend_header\n0 0 0\n");
  ExpectRefused(Creases(ply), {"huge.ply", "need at least 600000000 bytes"}, Out());
  WriteText(ply, BinaryPly("3", "1", std::string(72, '\0') + "\xff\xff\xff\x7f", "uint"));
  ExpectRefused(Creases(ply), {"huge.ply", "face 0: bad list length 2147483647"}, Out());
  WriteText(ply, BinaryPly("3", "2", std::string(72, '\0') + std::string("\x03\0\0\0\0\x01\0\0\0\x02\0\0\0\x03", 14)));
  ExpectRefused(Creases(ply), {"huge.ply", "face 1: bad list length 3"}, Out());
}

TEST_F(BadMesh, PlyAndObjContents) {
  const fs::path ply = dir_ / "bad.ply";
  WriteText(ply, "");
  ExpectRefused(Creases(ply), {"bad.ply", "PLY file is empty"}, Out());
  fs::remove(ply);
  fs::create_directories(ply);
  ExpectRefused(Creases(ply), {"bad.ply", "is a folder"}, Out());
  fs::remove(ply);
  WriteText(ply, "solid cube\nfacet normal 0 0 1\n");
  ExpectRefused(Creases(ply), {"bad.ply", "not a PLY file"}, Out());
  WriteText(ply, "ply\nformat binary_middle_endian 1.0\nend_header\n");
  ExpectRefused(Creases(ply), {"bad.ply", "unknown PLY format 'binary_middle_endian'"}, Out());
  WriteText(ply, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  ExpectRefused(Creases(ply), {"bad.ply", "face 0: vertex index 7 out of range (3 vertices)"}, Out());
  WriteText(ply, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                 "end_header\n0 nan 0\n");
  ExpectRefused(Creases(ply), {"bad.ply", "vertex 0: coordinate is not finite"}, Out());
  const fs::path obj = dir_ / "bad.obj";
  WriteText(obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
  ExpectRefused(Creases(obj), {"bad.obj", "line 4", "face index 4 out of range"}, Out());
  WriteText(obj, "v 0 0\n");
  ExpectRefused(Creases(obj), {"bad.obj", "line 1", "malformed vertex"}, Out());
  WriteText(dir_ / "mesh.stl", "solid\n");
  ExpectRefused(Creases(dir_ / "mesh.stl"), {"mesh.stl", "unknown mesh format '.stl'"}, Out());
}

TEST_F(BadMesh, Export) {
  const fs::path run = dir_ / "run", out = dir_ / "products";
  const std::string args = " --out " + out.string() + " --formats ply,dsm";
  ExpectRefused("export " + (dir_ / "nowhere").string() + args, {"nowhere", "no such run folder"}, out);
  fs::create_directories(run);
  ExpectRefused("export " + run.string() + args, {"surface.ply", "missing"}, out);
  WriteText(run / "surface.ply", BinaryPly("4000000000", "0", ""));
  ExpectRefused("export " + run.string() + args, {"surface.ply", "need at least"}, out);
  WritePly((run / "surface.ply").string(), Triangle());
  ExpectRefused("export " + run.string() + args, {"surface.ply", "no vertex colours"}, out);
  ExpectRefused("export " + run.string() + " --out " + out.string() + " --formats ply,stl", {"'stl'"}, out);
}

// A truth folder as `facets render` writes it, reduced to what `facets evaluate` reads:
// truth.json, truth.ply and a COLMAP model in sparse/.
fs::path WriteTruth(const fs::path& dir) {
  const fs::path truth = dir / "truth";
  WriteText(truth / "truth.json", "{\"ground_pixel_size\": 0.1}\n");
  WritePly((truth / "truth.ply").string(), Triangle());
  WriteText(truth / "sparse" / "cameras.txt", "1 PINHOLE 64 48 60 60 32 24\n");
  WriteText(truth / "sparse" / "images.txt", "1 1 0 0 0 0 0 10 1 a.png\n\n");
  return truth;
}

TEST_F(BadMesh, Evaluate) {
  const fs::path truth = WriteTruth(dir_);
  const fs::path json = dir_ / "report.json";
  const fs::path mesh = dir_ / "mesh.ply";
  MeshData no_faces = Triangle();
  no_faces.faces.clear();
  WritePly(mesh.string(), no_faces);
  const std::string tail = " --mesh " + mesh.string() + " --json " + json.string();
  ExpectRefused("evaluate --truth " + truth.string() + tail, {"mesh.ply", "has no faces (3 vertices)"}, json);
  WritePly(mesh.string(), Triangle());
  ExpectRefused("evaluate --truth " + truth.string() + tail + " --roi 0 0 1 1 1 0",
                {"--roi", "zmin 1 is not below zmax 0"}, json);
  fs::remove(truth / "truth.json");
  ExpectRefused("evaluate --truth " + truth.string() + tail, {"truth.json", "not found"}, json);
  WriteTruth(dir_);
  WriteText(truth / "sparse" / "images.txt", "# no images\n");
  ExpectRefused("evaluate --truth " + truth.string() + tail, {"images.txt", "is empty"}, json);
  ExpectRefused("evaluate --truth " + (dir_ / "nowhere").string() + tail, {"nowhere"}, json);
}

TEST_F(BadMesh, Render) {
  const fs::path scene = dir_ / "scene.json", out = dir_ / "rendered";
  const std::string args = "render " + scene.string() + " --out " + out.string();
  ExpectRefused(args, {"scene.json", "scene file not found"}, out);
  WriteText(scene, "{\"name\": \"x\", ");
  ExpectRefused(args, {"scene.json", "invalid JSON"}, out);
  WriteText(scene, "{\"name\": \"x\"}");
  ExpectRefused(args, {"scene.json", "ground_pixel_size"}, out);
  fs::remove(scene);
  fs::create_directories(scene);
  ExpectRefused(args, {"scene.json", "is a folder"}, out);
}

// The bundled stereo pair's scene (two small cropped frames: renders in about a second).
std::string PairScene() { return FileText(fs::path(FACETS_SOURCE_DIR) / "scenes/data/seed_gable_parallel.json"); }

std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

// A misspelt key of the scene file is an error naming it and the nearest known key, at
// the top level and inside an object.
TEST_F(BadMesh, RenderUnknownSceneKeys) {
  const fs::path scene = dir_ / "scene.json", out = dir_ / "rendered";
  const std::string args = "render " + scene.string() + " --out " + out.string();
  WriteText(scene, Replaced(PairScene(), "\"noise_sigma\"", "\"noise_sgima\""));
  ExpectRefused(args, {"scene.json: top level: unknown key 'noise_sgima' (nearest known key: 'noise_sigma')"}, out);
  WriteText(scene, Replaced(PairScene(), "\"focal_mm\"", "\"focal_mn\""));
  ExpectRefused(args, {"scene.json: /cameras: unknown key 'focal_mn' (nearest known key: 'focal_mm')"}, out);
  WriteText(scene, Replaced(PairScene(), "\"slope_deg\"", "\"file\": \"x.ply\", \"slope_deg\""));
  ExpectRefused(args, {"scene.json: /surface/1: unknown key 'file'"}, out);
}

// The render's output folder is replaced as a whole: a render that fails after it has
// started leaves the previous output byte for byte and no temporary folder beside it; a
// folder of other files is not replaced.
TEST_F(BadMesh, RenderOutputFolderIsAUnit) {
  const fs::path scene = dir_ / "scene.json", out = dir_ / "rendered";
  const std::string args = "render " + scene.string() + " --out " + out.string() + " --supersampling 1";
  WriteText(scene, PairScene());
  ASSERT_EQ(RunFacets(args).status, 0);
  const auto before = FolderSnapshot(out);
  ASSERT_TRUE(before.count("project.json") && before.count("images/img_00.png"));
  WriteText(dir_ / "broken.ply", "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n");
  WriteText(scene, Replaced(PairScene(), "\"type\": \"gable_roof\",", "\"type\": \"mesh\", \"file\": \"broken.ply\","));
  const Outcome failed = RunFacets(args);
  std::cout << "  -> status " << failed.status << ": " << failed.err;
  EXPECT_EQ(failed.status, 1);
  EXPECT_NE(failed.err.find("broken.ply"), std::string::npos) << failed.err;
  EXPECT_NE(failed.err.find(out.string() + " is unchanged"), std::string::npos) << failed.err;
  EXPECT_TRUE(FolderSnapshot(out) == before);
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find("rendered.facets-tmp"), std::string::npos) << entry.path();
  }
  const fs::path mine = dir_ / "mine";
  WriteText(mine / "notes.txt", "mine");
  WriteText(scene, PairScene());
  const Outcome refused = RunFacets("render " + scene.string() + " --out " + mine.string());
  EXPECT_EQ(refused.status, 1);
  EXPECT_NE(refused.err.find(mine.string() + ": holds files but no earlier run's output"), std::string::npos)
      << refused.err;
  EXPECT_EQ(FileText(mine / "notes.txt"), "mine");
}

// SIGINT or SIGTERM at the first moment the program can act on one (sent right after the
// start with the signal blocked, so it waits through the loading of the program): the
// clean message and status of a stopped run, not a death by signal, and nothing written.
TEST(BadSignal, StopDuringStartUpSaysSoWithTheStatusOfAStop) {
  const fs::path dir = CaseFolder();
  const fs::path out = dir / "run", err = dir / "err.txt";
  for (const int signal_number : {SIGINT, SIGTERM}) {
    // Blocked before the fork: the child holds it blocked from its first instruction.
    sigset_t blocked, previous;
    sigemptyset(&blocked);
    sigaddset(&blocked, signal_number);
    ASSERT_EQ(sigprocmask(SIG_BLOCK, &blocked, &previous), 0);
    const pid_t pid = fork();
    if (pid != 0) sigprocmask(SIG_SETMASK, &previous, nullptr);
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      const int fd = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, STDERR_FILENO);
      const std::string project = (dir / "project.json").string(), out_arg = out.string();
      execl(FACETS_CLI, FACETS_CLI, "reconstruct", "--project", project.c_str(), "--out", out_arg.c_str(),
            static_cast<char*>(nullptr));
      _exit(127);
    }
    ASSERT_EQ(kill(pid, signal_number), 0);
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    const std::string name = signal_number == SIGINT ? "SIGINT" : "SIGTERM";
    ASSERT_TRUE(WIFEXITED(status)) << name << ": ended by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    EXPECT_EQ(WEXITSTATUS(status), 128 + signal_number) << name;
    EXPECT_EQ(FileText(err), "facets: error: stopped by " + name + "\n");
    EXPECT_TRUE(FilesBelow(out).empty());
  }
}

}  // namespace
}  // namespace facets::bad_input
