#include "checkpoint.hpp"

#include <cstdint>
#include <fstream>
#include <sstream>

#include "granuflow/errors.hpp"

namespace granuflow::detail {

namespace {

constexpr char kMagic[] = "granuflow checkpoint 1\n";

class Writer {
 public:
  explicit Writer(std::ofstream& f) : f_(f) {}
  void u64(uint64_t v) { f_.write(reinterpret_cast<const char*>(&v), sizeof v); }
  void num(double v) { f_.write(reinterpret_cast<const char*>(&v), sizeof v); }
  void str(const std::string& s) { u64(s.size()), f_.write(s.data(), std::streamsize(s.size())); }
  void vec(const std::vector<double>& v) {
    u64(v.size());
    f_.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(double)));
  }
  void vecs(const std::vector<std::vector<double>>& v) {
    u64(v.size());
    for (const auto& x : v) vec(x);
  }

 private:
  std::ofstream& f_;
};

class Reader {
 public:
  Reader(std::ifstream& f, std::string path) : f_(f), path_(std::move(path)) {}
  uint64_t u64() {
    uint64_t v = 0;
    get(&v, sizeof v);
    return v;
  }
  double num() {
    double v = 0;
    get(&v, sizeof v);
    return v;
  }
  std::string str() {
    std::string s(size(1), '\0');
    get(s.data(), s.size());
    return s;
  }
  std::vector<double> vec() {
    std::vector<double> v(size(sizeof(double)));
    get(v.data(), v.size() * sizeof(double));
    return v;
  }
  std::vector<std::vector<double>> vecs() {
    std::vector<std::vector<double>> v(size(8));
    for (auto& x : v) x = vec();
    return v;
  }

 private:
  size_t size(size_t item) {
    const uint64_t n = u64();
    if (n > (uint64_t(1) << 40) / item) bad();
    return size_t(n);
  }
  void get(void* p, size_t n) {
    f_.read(static_cast<char*>(p), std::streamsize(n));
    if (!f_) bad();
  }
  [[noreturn]] void bad() const {
    throw ConfigError("restart " + path_ + ": the file ends early or is damaged (not a complete granuflow checkpoint)");
  }
  std::ifstream& f_;
  std::string path_;
};

}  // namespace

std::string structure_signature(const Flowsheet& fs, const SimOptions& opt) {
  std::ostringstream os;
  for (const auto& s : fs.state_names()) os << s << ',';
  os << '|';
  for (const auto& s : fs.output_names()) os << s << ',';
  os << '|' << fs.n_quadratures() << '|';
  for (const auto& s : opt.sensitivities) os << s << ',';
  os << '|';
  for (const auto& e : opt.events) os << e.name << ',';
  return os.str();
}

std::string checkpoint_path(const std::string& dir, double t) {
  std::ostringstream os;
  os.precision(12);
  os << dir << (dir.empty() || dir.back() == '/' ? "" : "/") << "checkpoint_" << t << "s.gfckpt";
  return os.str();
}

void write_checkpoint(const std::string& path, const Checkpoint& c) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw ConfigError("checkpoint " + path + ": cannot be written (is the output folder writable?)");
  Writer w(f);
  f.write(kMagic, sizeof kMagic - 1);
  w.str(c.scene), w.str(c.structure);
  w.u64(uint64_t(c.states)), w.u64(c.segment), w.u64(c.next_output);
  const StepperState& s = c.state;
  w.num(s.t), w.vec(s.y), w.vec(s.yp), w.vec(s.q), w.vecs(s.yS), w.vecs(s.ypS), w.vecs(s.qS);
  const SimResult& r = c.partial;
  w.vec(r.t), w.vec(r.y), w.vec(r.yp), w.vec(r.outputs), w.vec(r.sens), w.vec(r.output_sens);
  w.u64(r.events.size());
  for (const auto& e : r.events) w.str(e.name), w.str(e.phase), w.num(e.t);
  if (!f) throw ConfigError("checkpoint " + path + ": writing failed (disk full?)");
}

Checkpoint read_checkpoint(const std::string& path, const Flowsheet& fs, const SimOptions& opt) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw ConfigError("restart " + path + ": no such file (or it cannot be read)");
  std::string magic(sizeof kMagic - 1, '\0');
  f.read(magic.data(), std::streamsize(magic.size()));
  if (!f || magic != kMagic) throw ConfigError("restart " + path + ": not a granuflow checkpoint file");
  Reader r(f, path);
  Checkpoint c;
  c.scene = r.str(), c.structure = r.str();
  c.states = long(r.u64());
  if (c.scene != fs.name() || c.structure != structure_signature(fs, opt))
    throw ConfigError("restart " + path + ": written by scene '" + c.scene + "' (" + std::to_string(c.states) +
                      " states), not by this one ('" + fs.name() + "', " + std::to_string(fs.n_states()) +
                      " states) with the same structure, sensitivities and events: a checkpoint restarts only the "
                      "scene that wrote it");
  c.segment = r.u64(), c.next_output = r.u64();
  StepperState& s = c.state;
  s.t = r.num(), s.y = r.vec(), s.yp = r.vec(), s.q = r.vec(), s.yS = r.vecs(), s.ypS = r.vecs(), s.qS = r.vecs();
  SimResult& p = c.partial;
  p.t = r.vec(), p.y = r.vec(), p.yp = r.vec(), p.outputs = r.vec(), p.sens = r.vec(), p.output_sens = r.vec();
  const uint64_t ne = r.u64();
  for (uint64_t i = 0; i < ne && i < 1000000; ++i) {
    EventRecord e;
    e.name = r.str(), e.phase = r.str(), e.t = r.num();
    p.events.push_back(e);
  }
  if (!(s.t > 0) || !(s.t < opt.t_end))
    throw ConfigError("restart " + path + ": written at t = " + fmt_num(s.t) + " s, which is not before this run's " +
                      "t_end = " + fmt_num(opt.t_end) + " s");
  return c;
}

}  // namespace granuflow::detail
