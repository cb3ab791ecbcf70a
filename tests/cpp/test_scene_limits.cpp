// The scene loader's limits and refusals (scene.cpp, flowsheet.cpp): every hostile or mistaken file ends in one
// ConfigError line naming the file and what is wrong, quickly and without building what the file describes.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <fstream>

#include "granuflow/errors.hpp"
#include "scene_helpers.hpp"

namespace granuflow {
namespace {

using testing::repo_path;
using testing::scene_from_file;

const char* kTanks = R"(
scene: tanks
t_end: 100 s
units:
  feed: {type: liquid_feed, params: {mdot: 0.5 kg/s}}
  tank: {type: stirred_tank, params: {mass: 10 kg}}
  product: {type: liquid_product}
connections: [feed.out -> tank.in, tank.out -> product.in]
)";

// The message of the ConfigError that loading `text` throws ("" if none).
std::string refusal(const std::string& text) {
  try {
    load_scene_text(text, "s.yaml", units::builtin());
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    EXPECT_EQ(m.rfind("s.yaml: ", 0), 0u) << m;
    return m;
  }
  return "";
}

void expect_refused(const std::string& text, std::initializer_list<const char*> words) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string m = refusal(text);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 20.0)
      << m;  // a hang, not a slow parse (sanitizers)
  ASSERT_FALSE(m.empty()) << "accepted: " << text.substr(0, 200);
  for (const char* w : words) EXPECT_NE(m.find(w), std::string::npos) << w << " not in: " << m;
}

TEST(SceneLimits, AliasBombIsRefusedBeforeAnythingExpandsIt) {
  // 10^9 leaves in 9 lines; the emitter of the free-form keys would walk all of them.
  std::string t = std::string(kTanks) + "a0: &a0 [1,1,1,1,1,1,1,1,1,1]\n";
  for (int k = 1; k < 9; ++k) {
    const std::string p = "*a" + std::to_string(k - 1);
    t += "a" + std::to_string(k) + ": &a" + std::to_string(k) + " [";
    for (int j = 0; j < 10; ++j) t += (j ? "," : "") + p;
    t += "]\n";
  }
  t += "plots: [*a8]\n";
  expect_refused(t, {"line 14", "more than 200000 values", "alias"});
}

TEST(SceneLimits, ShapeAndEncoding) {
  expect_refused(std::string(kTanks) + "plots: &p [1, *p]\n", {"cycle"});
  expect_refused(std::string(kTanks) + "plots: " + std::string(5000, '[') + std::string(5000, ']') + "\n",
                 {"deeper than 64"});
  expect_refused(std::string(kTanks) + "notes: !!python/object:os.system x\n", {"tag '!!python/object:os.system'"});
  expect_refused(std::string(kTanks) + "notes: !custom x\n", {"tag '!custom'"});
  expect_refused("scene: caf\xe9\n", {"line 1, column 11", "0xe9 is not UTF-8"});
  expect_refused("scene: \xed\xa0\x80\n", {"0xed is not UTF-8"});  // a UTF-16 surrogate
  expect_refused("scene: a\n\x01\x02", {"line 2, column 1", "control byte 0x01"});
  expect_refused(std::string(kTanks) + "---\nscene: b\n", {"more than one YAML document"});
  expect_refused(std::string(2 << 20, '#'), {"at most 1048576 bytes"});
  expect_refused(std::string(kTanks) + "[a, b]: 1\n", {"a key must be a plain name, got a list"});
  expect_refused(std::string(kTanks) + "summary: {{a: 1}: tank.T}\n", {"summary", "got a mapping"});
  expect_refused(std::string(kTanks) + "notes: [\n", {"not valid YAML"});
  // Messages show at most 60 characters of what was written, on one line.
  expect_refused(std::string(kTanks) + "output: {n: \"" + std::string(5000, '9') + "x\"}\n", {"output.n", "..."});
  EXPECT_LT(refusal(std::string(kTanks) + "output: {n: \"" + std::string(5000, '9') + "x\"}\n").size(), 300u);
  expect_refused(std::string(kTanks) + "output: {n: \"1\\n2\"}\n", {"'1\\n2'"});
}

TEST(SceneLimits, OutputSizesAreCapped) {
  expect_refused(std::string(kTanks) + "output: {n: 1000000000}\n", {"output.n = 1000000000", "n_out <= 100000"});
  std::string times = "output: {times: [";
  for (int k = 0; k <= kMaxOutputTimes; ++k) times += (k ? "," : "") + std::to_string(k * 1e-4);
  expect_refused(std::string(kTanks) + times + "]}\n", {"output.times", "at most 100000"});
}

TEST(SceneLimits, OnlyRegularFilesAreRead) {
  auto message = [](const std::string& path) -> std::string {
    try {
      load_scene(path, units::builtin());
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message(repo_path("flowsheets")).find("is a directory"), std::string::npos);
  EXPECT_NE(message("/dev/null").find("not a regular file"), std::string::npos);
  EXPECT_NE(message("/nonexistent/scene.yaml").find("No such file or directory"), std::string::npos);
  const std::string fifo = ::testing::TempDir() + "granuflow_fifo.yaml";
  std::remove(fifo.c_str());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(message(fifo).find("not a regular file"), std::string::npos);  // and no hang opening it
  std::remove(fifo.c_str());
}

TEST(SceneLimits, ParamsAndInputsOfOneParameterAreRefused) {
  std::string t = kTanks;
  t.replace(t.find("{mdot: 0.5 kg/s}"), 16, "{mdot: 0.5 kg/s, T: 300 K}");
  expect_refused(t + "inputs: {feed.T: {times: [0 s, 10 s], values: [300 K, 350 K]}}\n",
                 {"inputs.feed.T", "units.feed.params.T", "remove one of them"});
}

TEST(SceneLimits, InputDrivenParameterCannotBeSetSilently) {
  Scene s = load_scene_text(std::string(kTanks) + "inputs: {feed.T: {times: [0 s, 10 s], values: [300 K, 350 K]}}\n",
                            "s.yaml", units::builtin());
  Flowsheet& fs = *s.flowsheet;
  try {
    fs.set_param("feed.T", 310.0);
    FAIL() << "set on an input-driven parameter was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("driven by the time-dependent input feed.T"), std::string::npos) << e.what();
  }
  // The explicit way: remove the input, then the constant counts.
  fs.clear_input("feed.T");
  fs.set_param("feed.T", 310.0);
  const SimResult r = simulate(fs, s.options);
  EXPECT_NEAR(r.state(r.t.size() - 1, fs.state_id("feed.T")), 310.0, 1e-9);
}

TEST(SceneLimits, LinkNarrowsTheSourceToWhatItsFollowerAccepts) {
  Scene s = scene_from_file("flowsheets/stoeckl_gf25_batch.yaml");
  Flowsheet& fs = *s.flowsheet;
  const int id = fs.param_id("inlet.T");
  EXPECT_EQ(fs.param_spec(id).upper, 600.0);  // declared
  EXPECT_EQ(fs.bounds(id).second, 500.0);     // bed.T0 <= 500 K follows it
  try {
    fs.set_param("inlet.T", 550.0);
    FAIL() << "inlet.T = 550 K accepted although bed.T0 cannot start there";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("bed.T0 in [250, 500] follows it by a link"), std::string::npos) << e.what();
  }
  fs.set_param("inlet.T", 480.0);
  EXPECT_EQ(fs.param("bed.T0"), 480.0);
}

TEST(SceneLimits, SupersaturatedInletAirIsRefusedAlsoWhenAnInputRampsIntoIt) {
  const std::string gf = [] {
    std::ifstream f(repo_path("flowsheets/stoeckl_gf25_batch.yaml"));
    return std::string(std::istreambuf_iterator<char>(f), {});
  }();
  Scene s = load_scene_text(gf, "gf.yaml", units::builtin());
  s.flowsheet->set_param("inlet.Y", 0.005);
  s.flowsheet->set_param("inlet.T", 250.0);  // inside every bound, but 930 % relative humidity
  try {
    s.flowsheet->check_units();
    FAIL() << "supersaturated inlet air accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("inlet.Y = 0.005 kg/kg: violates Y <= saturation humidity"), std::string::npos)
        << e.what();
  }
  // 100 degC air holds any humidity at 1 atm.
  s.flowsheet->set_param("inlet.T", 380.0);
  s.flowsheet->set_param("inlet.Y", 0.4);
  EXPECT_NO_THROW(s.flowsheet->check_units());
  // Only values a run sees are checked: under an input on inlet.T its stored constant (60 degC, at which
  // 0.2 kg/kg would be supersaturated) is never used.
  Scene h = load_scene_text(gf, "gf.yaml", units::builtin());
  h.flowsheet->set_input("inlet.T",
                         PiecewiseLinear({0.0, 600.0}, {400.0, 380.0}, PiecewiseLinear::Interp::kLinear, "input"));
  h.flowsheet->set_param("inlet.Y", 0.2);
  EXPECT_NO_THROW(h.flowsheet->check_units());
  std::string t = gf + "\n";
  t.erase(t.find("T: 60 degC, "), 12);  // the input replaces it
  const auto links = t.find("\nlinks:") + 1;
  t.insert(links, "inputs:\n  inlet.T: {times: [0 s, 600 s], values: [330 K, 260 K]}\n");
  const std::string m = refusal(t);
  EXPECT_NE(m.find("units.inlet.params.Y = 0.005 kg/kg"), std::string::npos) << m;
  EXPECT_NE(m.find("saturation humidity"), std::string::npos) << m;
  EXPECT_NE(m.find("at t = 600 s of the inputs inlet.T"), std::string::npos) << m;
}

}  // namespace
}  // namespace granuflow
