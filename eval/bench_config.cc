/// @file bench_config.cc
#include "eval/bench_config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "eval/sim_ceiling.h"
#include "scene/strict_yaml_reader.h"

namespace p2i::eval {
namespace fs = std::filesystem;
namespace {

using Reader = scene::StrictYamlReader;

int Int(const Reader& r, const YAML::Node& n, const std::string& what, int min_value) {
  const double v = r.Double(n, what);
  if (v != static_cast<int>(v)) r.Fail(n, what + " must be an integer");
  if (v < min_value) r.Fail(n, what + " must be >= " + std::to_string(min_value));
  return static_cast<int>(v);
}

bool Bool(const Reader& r, const YAML::Node& n, const std::string& what) {
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    r.Fail(n, what + " must be true or false");
  }
}

std::vector<std::string> Strings(const Reader& r, const YAML::Node& n, const std::string& what) {
  std::vector<std::string> out;
  if (n.IsScalar()) return {r.String(n, what)};
  if (!n.IsSequence()) r.Fail(n, what + " must be a string or a list of strings");
  for (const auto& e : n) out.push_back(r.String(e, what));
  return out;
}

std::vector<double> Doubles(const Reader& r, const YAML::Node& n, const std::string& what) {
  if (!n.IsSequence() || n.size() == 0) r.Fail(n, what + " must be a non-empty list of numbers");
  std::vector<double> out;
  for (const auto& e : n) out.push_back(r.Double(e, what));
  for (size_t i = 1; i < out.size(); ++i)
    if (out[i] <= out[i - 1]) r.Fail(n, what + " must be strictly increasing");
  return out;
}

// A YAML map of P2iConfig overrides as text ("" when absent).
std::string OverrideMap(const Reader& r, const YAML::Node& n, const std::string& what) {
  if (!n.IsDefined() || n.IsNull()) return "";
  r.CheckMap(n, what);
  YAML::Emitter e;
  e << n;
  return e.c_str();
}

scene::EvalSetting Setting(const Reader& r, const YAML::Node& n, const std::string& what) {
  const std::string name = r.String(n, what);
  try {
    return scene::EvalSetting::Parse(name);
  } catch (const std::invalid_argument& e) {
    r.Fail(n, std::string(e.what()) + " in " + what);
  }
}

std::vector<scene::EvalSetting> Settings(const Reader& r, const YAML::Node& n,
                                         const std::string& what) {
  if (n.IsScalar()) return {Setting(r, n, what)};
  if (!n.IsSequence()) r.Fail(n, what + " must be a setting or a list of settings");
  std::vector<scene::EvalSetting> out;
  for (const auto& e : n) out.push_back(Setting(r, e, what));
  return out;
}

bool Contains(const std::vector<scene::EvalSetting>& v, const scene::EvalSetting& x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

}  // namespace

std::string ResolvePreset(const std::string& preset, const std::string& config_dir) {
  std::vector<std::string> tried;
  auto consider = [&](const fs::path& p) {
    tried.push_back(p.string());
    return fs::is_regular_file(p);
  };
  if (consider(preset)) return preset;
  if (!config_dir.empty() && consider(fs::path(config_dir) / preset))
    return (fs::path(config_dir) / preset).string();
  const fs::path presets = fs::path(P2I_EVAL_SOURCE_DIR) / "model" / "presets";
  if (consider(presets / (preset + ".yaml"))) return (presets / (preset + ".yaml")).string();
  std::string list;
  for (const auto& t : tried) list += (list.empty() ? "" : ", ") + t;
  throw std::runtime_error("preset '" + preset + "' not found (looked at " + list + ")");
}

BenchConfig BenchConfig::FromYamlFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read bench config " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  return FromYamlString(ss.str(), path);
}

namespace {

// dataset: a sim scene or a dataset folder (exactly one), and how frames are taken.
void ReadDataset(const Reader& r, const YAML::Node& root, const std::string& config_dir,
                 BenchConfig& c) {
  const YAML::Node ds = r.Require(root, "dataset", "the bench config");
  r.CheckKeys(ds,
              {"scene", "path", "format", "seven_scenes_invalid_depth", "sequences", "trajectories",
               "trajectory_offset", "heights", "speed", "max_frames", "frame_step", "render_size",
               "sensor", "specular"},
              "dataset");
  auto& d = c.dataset;
  if (ds["scene"]) d.scene = r.String(ds["scene"], "dataset.scene");
  if (ds["path"]) d.path = r.String(ds["path"], "dataset.path");
  if (d.scene.empty() == d.path.empty())
    r.Fail(ds, "dataset needs exactly one of 'scene' (a sim scene: builtin:NAME or a scene YAML) "
               "and 'path' (a dataset folder)");
  if (!d.path.empty() && fs::path(d.path).is_relative() && !fs::exists(d.path) &&
      fs::exists(fs::path(config_dir) / d.path))
    d.path = (fs::path(config_dir) / d.path).string();
  if (ds["format"]) d.format = r.String(ds["format"], "dataset.format");
  if (ds["seven_scenes_invalid_depth"])
    d.seven_scenes_invalid_depth =
        Int(r, ds["seven_scenes_invalid_depth"], "dataset.seven_scenes_invalid_depth", 0);
  if (ds["sequences"]) {
    if (d.path.empty()) r.Fail(ds["sequences"], "dataset.sequences needs dataset.path");
    const YAML::Node seqs = ds["sequences"];
    if (!seqs.IsSequence() || seqs.size() == 0)
      r.Fail(seqs, "dataset.sequences must be a non-empty list of sequence names, e.g. [seq-01]");
    for (const auto& s : seqs) d.sequences.push_back(r.String(s, "dataset.sequences"));
  }
  if (ds["trajectories"]) d.trajectories = Int(r, ds["trajectories"], "dataset.trajectories", 1);
  if (ds["trajectory_offset"])
    d.trajectory_offset = r.Double(ds["trajectory_offset"], "dataset.trajectory_offset");
  if (ds["heights"]) d.heights = Doubles(r, ds["heights"], "dataset.heights");
  if (ds["speed"]) d.speed = r.Double(ds["speed"], "dataset.speed");
  if (ds["max_frames"]) d.max_frames = Int(r, ds["max_frames"], "dataset.max_frames", 0);
  if (ds["frame_step"]) d.frame_step = Int(r, ds["frame_step"], "dataset.frame_step", 1);
  if (ds["render_size"]) d.render_size = Int(r, ds["render_size"], "dataset.render_size", 16);
  if (ds["sensor"]) d.sensor = scene::SimSensorOptions::FromYaml(ds["sensor"], c.source);
  if (ds["specular"]) d.specular = Bool(r, ds["specular"], "dataset.specular");
}

// settings (parsed once into scene::EvalSetting), period, split_b / split_c, max_test_views.
void ReadSettings(const Reader& r, const YAML::Node& root, BenchConfig& c) {
  c.settings = Settings(r, r.Require(root, "settings", "the bench config"), "settings");
  if (root["period"]) c.period = Int(r, root["period"], "period", 2);
  for (const auto& s : c.settings)
    if (s.held_out >= c.period)
      r.Fail(root["settings"], "setting " + s.Name() + " holds out N >= period (" +
                                   std::to_string(c.period) + " frames): raise 'period'");
  if (root["split_b"]) {
    const YAML::Node b = root["split_b"];
    r.CheckKeys(b, {"train", "test"}, "split_b");
    c.b_train = r.String(r.Require(b, "train", "split_b"), "split_b.train");
    c.b_test = r.String(r.Require(b, "test", "split_b"), "split_b.test");
  }
  if (root["split_c"]) {
    const YAML::Node cc = root["split_c"];
    r.CheckKeys(cc, {"train", "test"}, "split_c");
    c.c_train = Strings(r, r.Require(cc, "train", "split_c"), "split_c.train");
    c.c_test = Strings(r, r.Require(cc, "test", "split_c"), "split_c.test");
  }
  if (root["max_test_views"]) c.max_test_views = Int(r, root["max_test_views"], "max_test_views", 1);
}

// sizes: the ladder (a resolution, or a map with model overrides and settings).
void ReadSizes(const Reader& r, const YAML::Node& root, BenchConfig& c) {
  const YAML::Node sizes = r.Require(root, "sizes", "the bench config");
  if (!sizes.IsSequence() || sizes.size() == 0) r.Fail(sizes, "sizes must be a non-empty list");
  std::set<std::string> size_names;
  for (const auto& s : sizes) {
    SizeSpec size;
    if (s.IsScalar()) {  // "128" or "r128" shorthand
      std::string v = s.as<std::string>();
      size.name = v;
      if (!v.empty() && v[0] == 'r') v = v.substr(1);
      try {
        size.resolution = std::stoi(v);
      } catch (const std::exception&) {
        r.Fail(s, "a size must be a resolution (e.g. 128) or a map {name, resolution, model}");
      }
    } else {
      r.CheckKeys(s, {"name", "resolution", "height", "model", "settings"}, "a size");
      if (s["settings"]) size.settings = Settings(r, s["settings"], "size settings");
      size.resolution = Int(r, r.Require(s, "resolution", "a size"), "size resolution", 16);
      if (s["height"]) size.height = Int(r, s["height"], "size height", 16);
      size.name = s["name"] ? r.String(s["name"], "size name")
                            : "r" + std::to_string(size.resolution) +
                                  (size.Square() ? "" : "x" + std::to_string(size.Height()));
      size.model_yaml = OverrideMap(r, s["model"], "size '" + size.name + "' model");
    }
    if (!size_names.insert(size.name).second) r.Fail(s, "size name '" + size.name + "' repeats");
    c.sizes.push_back(size);
  }
}

// seeds, threads, lpips_weights, strip_views.
void ReadRunOptions(const Reader& r, const YAML::Node& root, BenchConfig& c) {
  if (root["seeds"]) {
    c.seeds.clear();
    if (!root["seeds"].IsSequence() || root["seeds"].size() == 0)
      r.Fail(root["seeds"], "seeds must be a non-empty list of integers");
    for (const auto& s : root["seeds"]) c.seeds.push_back(Int(r, s, "seeds", 0));
  }
  if (root["threads"]) c.threads = Int(r, root["threads"], "threads", 1);
  if (root["lpips_weights"]) c.lpips_weights = r.String(root["lpips_weights"], "lpips_weights");
  if (root["strip_views"]) c.strip_views = Int(r, root["strip_views"], "strip_views", 0);
}

// ceiling: the kinds of sim ceiling rows (eval/sim_ceiling.h), sim scenes only.
void ReadCeiling(const Reader& r, const YAML::Node& root, BenchConfig& c) {
  const YAML::Node node = root["ceiling"];
  if (!node) return;
  if (!node.IsSequence()) r.Fail(node, "ceiling must be a list of kinds (" + CeilingKinds() + ")");
  if (!c.dataset.IsSim() && node.size() > 0)
    r.Fail(node, "ceiling needs a sim scene (dataset.scene): a captured dataset has no exact render "
                 "to compare with; remove the key");
  for (const auto& k : node) {
    const std::string kind = r.String(k, "ceiling");
    if (!IsCeilingKind(kind)) r.Fail(k, "ceiling kind '" + kind + "' is not one of " + CeilingKinds());
    if (std::find(c.ceiling.begin(), c.ceiling.end(), kind) != c.ceiling.end())
      r.Fail(k, "ceiling kind '" + kind + "' repeats");
    c.ceiling.push_back(kind);
  }
}

// methods: each a name of the method registry with its common, training and own keys.
void ReadMethods(const Reader& r, const YAML::Node& root, const std::string& config_dir,
                 BenchConfig& c) {
  const YAML::Node methods = r.Require(root, "methods", "the bench config");
  if (!methods.IsSequence() || methods.size() == 0)
    r.Fail(methods, "methods must be a non-empty list");
  std::set<std::string> names;
  for (const auto& m : methods) {
    MethodSpec spec;
    YAML::Node options;  // the method's own keys (model::MethodInfo::option_keys)
    if (m.IsScalar()) {
      spec.name = m.as<std::string>();
      spec.type = spec.name;
    } else {
      spec.name = r.String(r.Require(m, "name", "a method"), "method name");
      spec.type = m["type"] ? r.String(m["type"], "method type") : spec.name;
    }
    const model::MethodInfo* info = model::FindMethod(spec.type);
    if (info == nullptr)
      r.Fail(m, "method '" + spec.name + "' has unknown type '" + spec.type + "' (allowed: " +
                    model::MethodNames() + ")");
    spec.type = info->name;
    spec.learned = info->learned;
    if (m.IsMap()) {
      std::set<std::string> keys = {"name", "type"};
      if (info->learned)
        keys.insert({"preset", "config", "steps", "enet_steps", "batch_size", "seeds",
                     "seed_settings", "seed_sizes", "max_train_s"});
      keys.insert(info->option_keys.begin(), info->option_keys.end());
      r.CheckKeys(m, keys, "method '" + spec.name + "' (type " + spec.type + ")");
      if (m["preset"]) spec.preset = r.String(m["preset"], "method preset");
      spec.config_yaml = OverrideMap(r, m["config"], "method '" + spec.name + "' config");
      if (m["steps"]) spec.steps = Int(r, m["steps"], "method steps", 0);
      if (m["enet_steps"]) spec.enet_steps = Int(r, m["enet_steps"], "method enet_steps", 0);
      if (m["batch_size"]) spec.batch_size = Int(r, m["batch_size"], "method batch_size", 1);
      if (m["seeds"]) {
        for (const auto& s : m["seeds"]) spec.seeds.push_back(Int(r, s, "method seeds", 0));
      }
      if (m["seed_settings"])
        spec.seed_settings = Settings(r, m["seed_settings"], "method seed_settings");
      if (m["seed_sizes"]) spec.seed_sizes = Strings(r, m["seed_sizes"], "method seed_sizes");
      if (m["max_train_s"]) {
        spec.max_train_s = r.Double(m["max_train_s"], "method max_train_s");
        if (spec.max_train_s < 0) r.Fail(m["max_train_s"], "method max_train_s must be >= 0");
      }
      for (const auto& key : info->option_keys)
        if (m[key]) options[key] = m[key];
    }
    if (options.size() > 0) {
      YAML::Emitter e;
      e << options;
      spec.options_yaml = e.c_str();
    }
    // The options' source is the config file itself (a method resolves the files its options name
    // relative to it); the method is named when an option is refused.
    try {
      spec.make = info->configure(options, c.source);
    } catch (const std::exception& e) {
      throw std::runtime_error(std::string(e.what()) + " (method '" + spec.name + "')");
    }
    if (spec.IsLearned()) {
      if (spec.preset.empty()) spec.preset = info->default_preset;
      try {
        spec.preset = ResolvePreset(spec.preset, config_dir);
      } catch (const std::exception& e) {
        r.Fail(m, std::string("method '") + spec.name + "': " + e.what());
      }
    }
    if (!names.insert(spec.name).second) r.Fail(m, "method name '" + spec.name + "' repeats");
    c.methods.push_back(spec);
  }
}

// stability: the sweep and the (setting, size) whose models it probes (default: the first).
void ReadStability(const Reader& r, const YAML::Node& root, BenchConfig& c) {
  if (root["stability"]) {
    const YAML::Node s = root["stability"];
    r.CheckKeys(s, {"enabled", "translations_m", "rotations_deg", "poses", "threshold_db",
                    "setting", "size"},
                "stability");
    auto& st = c.stability;
    if (s["enabled"]) st.enabled = Bool(r, s["enabled"], "stability.enabled");
    if (s["translations_m"]) st.translations_m = Doubles(r, s["translations_m"], "stability.translations_m");
    if (s["rotations_deg"]) st.rotations_deg = Doubles(r, s["rotations_deg"], "stability.rotations_deg");
    if (s["poses"]) st.poses = Int(r, s["poses"], "stability.poses", 1);
    if (s["threshold_db"]) st.threshold_db = r.Double(s["threshold_db"], "stability.threshold_db");
  }
  const YAML::Node st_node = root["stability"];
  c.stability.setting = st_node && st_node["setting"]
                            ? Setting(r, st_node["setting"], "stability.setting")
                            : c.settings.front();
  if (st_node && st_node["size"]) c.stability.size = r.String(st_node["size"], "stability.size");
  if (c.stability.size.empty()) c.stability.size = c.sizes.front().name;
  if (!Contains(c.settings, c.stability.setting))
    r.Fail(root["stability"],
           "stability.setting '" + c.stability.setting.Name() + "' is not in settings");
  if (!c.FindSize(c.stability.size))
    r.Fail(root["stability"], "stability.size '" + c.stability.size + "' is not in sizes");
}

// auto_size: the method (default: the first learned one), setting and margin.
void ReadAutoSize(const Reader& r, const YAML::Node& root, BenchConfig& c) {
  if (root["auto_size"]) {
    const YAML::Node a = root["auto_size"];
    r.CheckKeys(a, {"method", "methods", "setting", "margin_db"}, "auto_size");
    if (a["method"]) c.auto_size.method = r.String(a["method"], "auto_size.method");
    if (a["methods"]) {
      if (!a["methods"].IsSequence() || a["methods"].size() < 2)
        r.Fail(a["methods"], "auto_size.methods must be a list of at least two method names");
      for (const auto& m : a["methods"]) {
        const std::string name = r.String(m, "auto_size.methods");
        if (!c.FindMethod(name))
          r.Fail(m, "auto_size.methods: '" + name + "' is not in methods");
        c.auto_size.methods.push_back(name);
      }
    }
    if (a["margin_db"]) c.auto_size.margin_db = r.Double(a["margin_db"], "auto_size.margin_db");
    if (c.auto_size.margin_db < 0) r.Fail(a, "auto_size.margin_db must be >= 0");
  }
  if (c.auto_size.method.empty())
    for (const auto& m : c.methods)
      if (m.IsLearned()) {
        c.auto_size.method = m.name;
        break;
      }
  const YAML::Node as_node = root["auto_size"];
  c.auto_size.setting = as_node && as_node["setting"]
                            ? Setting(r, as_node["setting"], "auto_size.setting")
                            : c.settings.front();
  if (!c.auto_size.method.empty() && !c.FindMethod(c.auto_size.method))
    r.Fail(root["auto_size"], "auto_size.method '" + c.auto_size.method + "' is not in methods");
}

// Names that refer to other entries (settings of sizes and methods, seed sizes) exist.
void CheckReferences(const Reader& r, const YAML::Node& root, const BenchConfig& c) {
  const YAML::Node sizes = root["sizes"];
  const YAML::Node methods = root["methods"];
  for (const auto& s : c.sizes)
    for (const auto& x : s.settings)
      if (!Contains(c.settings, x))
        r.Fail(sizes, "size '" + s.name + "' names setting '" + x.Name() +
                          "' which is not in settings");
  for (const auto& m : c.methods)
    for (const auto& x : m.seed_settings)
      if (!Contains(c.settings, x))
        r.Fail(methods, "method '" + m.name + "' seed_settings names '" + x.Name() +
                            "' which is not in settings");

  for (const auto& m : c.methods)
    for (const auto& x : m.seed_sizes)
      if (!c.FindSize(x))
        r.Fail(methods, "method '" + m.name + "' seed_sizes names '" + x + "' which is not in sizes");
}

}  // namespace

BenchConfig BenchConfig::FromYamlString(const std::string& text, const std::string& source) {
  BenchConfig c;
  c.source = source;
  c.text = text;
  const Reader r(source);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(source + ": YAML error: " + e.what());
  }
  r.CheckKeys(root,
              {"dataset", "settings", "period", "split_b", "split_c", "max_test_views", "methods",
               "sizes", "seeds", "threads", "lpips_weights", "strip_views", "stability",
               "auto_size", "ceiling"},
              "the bench config");
  const std::string config_dir = fs::path(source).parent_path().string();
  ReadDataset(r, root, config_dir, c);
  ReadSettings(r, root, c);
  ReadSizes(r, root, c);
  ReadRunOptions(r, root, c);
  ReadMethods(r, root, config_dir, c);
  ReadStability(r, root, c);
  ReadAutoSize(r, root, c);
  ReadCeiling(r, root, c);
  CheckReferences(r, root, c);
  // Build every learned model config now: a bad override stops the run at start-up.
  for (const auto& m : c.methods)
    if (m.IsLearned())
      for (const auto& s : c.sizes)
        if (s.Square()) (void)c.ModelConfig(m, s, c.SeedsOf(m).front());  // learned: square only
  return c;
}

model::P2iConfig BenchConfig::ModelConfig(const MethodSpec& method, const SizeSpec& size,
                                          int seed) const {
  YAML::Node node;
  try {
    node = YAML::LoadFile(method.preset);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(method.preset + ": YAML error: " + e.what());
  }
  auto apply = [&](const std::string& text) {
    if (text.empty()) return;
    const YAML::Node o = YAML::Load(text);
    for (const auto& kv : o) node[kv.first.as<std::string>()] = kv.second;
  };
  apply(size.model_yaml);
  apply(method.config_yaml);
  node["name"] = method.name + "_" + size.name;
  node["resolution"] = size.resolution;
  if (method.steps >= 0) node["steps_phase1"] = method.steps;
  const int enet = method.enet_steps >= 0 ? method.enet_steps
                   : method.steps >= 0    ? std::max(1, method.steps / 4)
                                          : -1;
  if (enet >= 0) node["steps_phase2"] = enet;
  if (method.batch_size > 0) node["batch_size"] = method.batch_size;
  node["seed"] = seed;
  const std::string& trained = model::GetMethod(method.type).trainer_model;
  if (!trained.empty()) node["model"] = trained;
  YAML::Emitter e;
  e << node;
  return model::P2iConfig::FromYamlString(
      e.c_str(), source + " (method '" + method.name + "' preset " + method.preset + ", size '" +
                     size.name + "')");
}

std::vector<int> BenchConfig::SeedsOf(const MethodSpec& method) const {
  if (!method.IsLearned()) return {seeds.front()};  // deterministic: one seed is enough
  return method.seeds.empty() ? seeds : method.seeds;
}

std::vector<int> BenchConfig::RunsOf(const MethodSpec& method, const scene::EvalSetting& setting,
                                     const SizeSpec& size) const {
  auto has = [](const auto& v, const auto& x) {
    return v.empty() || std::find(v.begin(), v.end(), x) != v.end();
  };
  if (!has(size.settings, setting)) return {};
  if (method.IsLearned() && !size.Square()) return {};  // the networks render square views
  if (!method.IsLearned()) {
    for (const auto& s : sizes) {
      if (&s == &size) break;
      if (s.Width() == size.Width() && s.Height() == size.Height() && has(s.settings, setting))
        return {};
    }
  }
  std::vector<int> seeds_here = SeedsOf(method);
  if (!has(method.seed_settings, setting) || !has(method.seed_sizes, size.name))
    seeds_here.resize(1);
  return seeds_here;
}

const MethodSpec* BenchConfig::FindMethod(const std::string& name) const {
  for (const auto& m : methods)
    if (m.name == name) return &m;
  return nullptr;
}

const SizeSpec* BenchConfig::FindSize(const std::string& name) const {
  for (const auto& s : sizes)
    if (s.name == name) return &s;
  return nullptr;
}

std::string BenchConfig::Hash() const {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char ch : text) {
    h ^= ch;
    h *= 1099511628211ull;
  }
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace p2i::eval
