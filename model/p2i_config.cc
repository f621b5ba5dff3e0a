/// @file p2i_config.cc
/// @brief YAML reading/writing and validation of P2iConfig.
#include "model/p2i_config.h"

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace p2i::model {

namespace {

bool IsPowerOfTwo(int v) { return v > 0 && (v & (v - 1)) == 0; }

int Log2(int v) {
  int n = 0;
  while ((1 << n) < v) ++n;
  return n;
}

}  // namespace

std::vector<int> P2iConfig::GeneratorWidths() const {
  const int stages = Log2(resolution) - 1;  // 4x4 .. resolution
  std::vector<int> widths;
  if (g_schedule == "custom") return g_widths;
  for (int i = 0; i < stages; ++i) {
    if (g_schedule == "fewer" || stages == 1) {
      widths.push_back(g_min_width);
    } else {
      const double t = static_cast<double>(i) / (stages - 1);
      const double w = g_min_width * std::pow(static_cast<double>(g_max_width) / g_min_width, t);
      widths.push_back(std::max(8, static_cast<int>(std::lround(w / 8.0)) * 8));
    }
  }
  return widths;
}

int P2iConfig::PoseInputs() const {
  if (pose_encoding != "fourier") return 7;
  if (fourier_bands == kAutoFourierBands)
    throw std::logic_error("P2iConfig '" + name + "': fourier_bands is still auto; training "
                           "chooses it from the training poses (a checkpoint's config holds "
                           "the chosen count)");
  return 7 * (1 + 2 * fourier_bands);
}

void P2iConfig::Validate() const {
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument("P2iConfig '" + name + "': " + what);
  };
  if (model != "p2i_net" && model != "cnn_baseline")
    fail("model must be p2i_net or cnn_baseline, got '" + model + "'");
  if (!IsPowerOfTwo(resolution) || resolution < 32 || resolution > 512)
    fail("resolution must be a power of two in [32, 512], got " + std::to_string(resolution));
  if (g_schedule != "more" && g_schedule != "fewer" && g_schedule != "custom")
    fail("g_schedule must be more, fewer or custom, got '" + g_schedule + "'");
  const int stages = Log2(resolution) - 1;
  if (g_schedule == "custom" && static_cast<int>(g_widths.size()) != stages)
    fail("g_widths needs log2(resolution) - 1 = " + std::to_string(stages) +
         " entries (4x4 .. resolution), got " + std::to_string(g_widths.size()));
  for (int w : GeneratorWidths())
    if (w <= 0) fail("g_widths entries must be positive");
  if (g_min_width <= 0 || g_max_width < g_min_width)
    fail("need 0 < g_min_width <= g_max_width");
  if (g_fc_width <= 0 || d_base_width <= 0 || d_max_width < d_base_width || latent_dim <= 0 ||
      mapping_width <= 0 || enet_width <= 0 || enet_blocks < 0 || attention_max_res < 1)
    fail("widths must be positive (g_fc_width, d_base_width <= d_max_width, latent_dim, "
         "mapping_width, enet_width, attention_max_res) and enet_blocks >= 0");
  if (batch_size < 1) fail("batch_size must be >= 1");
  if (d_steps < 1) fail("d_steps must be >= 1");
  if (!(g_ema >= 0 && g_ema < 1)) fail("g_ema must be in [0, 1) (0 = off)");
  if (g_norm != "none" && g_norm != "pixel") fail("g_norm must be none or pixel, got '" + g_norm + "'");
  if (pose_encoding != "none" && pose_encoding != "fourier")
    fail("pose_encoding must be none or fourier, got '" + pose_encoding + "'");
  if (fourier_bands != kAutoFourierBands && (fourier_bands < 1 || fourier_bands > 16))
    fail("fourier_bands must be in [1, 16] or auto, got " + std::to_string(fourier_bands));
  if (!(recon_weight >= 0)) fail("recon_weight must be >= 0 (0 = off)");
  if (!(r1_gamma >= 0)) fail("r1_gamma must be >= 0 (0 = off)");
  if (!(densify_ratio >= 0 && densify_ratio <= 100)) fail("densify_ratio must be in [0, 100] (0 = off)");
  if (!(densify_offset_m >= 0 && densify_offset_m <= 10)) fail("densify_offset_m must be in [0, 10] metres");
  if (!(densify_angle_deg >= 0 && densify_angle_deg <= 90)) fail("densify_angle_deg must be in [0, 90] degrees");
  if (densify_method.empty()) fail("densify_method must name a method (e.g. fusion or warp)");
  if (!(densify_min_gap_m >= 0 && densify_min_gap_m <= 10))
    fail("densify_min_gap_m must be in [0, 10] metres (0 = off)");
  if (!(densify_min_gap_deg >= 0 && densify_min_gap_deg <= 180))
    fail("densify_min_gap_deg must be in [0, 180] degrees");
  if (!(densify_real_share >= 0 && densify_real_share < 1))
    fail("densify_real_share must be in [0, 1) (0 = off; 1 would never show a densified view: "
         "set densify_ratio 0 instead)");
  if (densify_steps < -1) fail("densify_steps must be >= -1 (-1 = densified views in every step)");
  if (steps_phase1 < 0 || steps_phase2 < 0) fail("steps_phase1/2 must be >= 0");
  if (!(lr_g > 0 && lr_d > 0 && lr_enet > 0)) fail("learning rates must be > 0");
  if (lr_decay_steps < 0) fail("lr_decay_steps must be >= 0 (0 = constant learning rates)");
  if (!(beta1 >= 0 && beta1 < 1 && beta2 >= 0 && beta2 < 1)) fail("betas must be in [0, 1)");
  if (!(depth_max > 0)) fail("depth_max must be > 0 metres");
  if (val_every < 1 || checkpoint_every < 1) fail("val_every and checkpoint_every must be >= 1");
  if (!(explode_factor > 1)) fail("explode_factor must be > 1");
  if (k1 < 0 || k2 < 0 || k3 < 0) fail("k1, k2, k3 must be >= 0");
}

namespace {

std::string ReadConfigText(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("model config: cannot open '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The config text as a YAML map; errors name `source`.
YAML::Node LoadConfigMap(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error("model config " + source + ": YAML error: " + e.what());
  }
  if (!root.IsMap()) throw std::runtime_error("model config " + source + ": expected a map");
  return root;
}

/// `fourier_bands`: a count, or "auto" (kAutoFourierBands).
int FourierBands(const YAML::Node& n, const std::string& source) {
  if (n.IsScalar() && n.Scalar() == "auto") return kAutoFourierBands;
  int bands = 0;
  if (!YAML::convert<int>::decode(n, bands) || bands == kAutoFourierBands)
    throw std::runtime_error("model config " + source + ": bad value for 'fourier_bands': "
                             "expected a number in [1, 16] or auto");
  return bands;
}

}  // namespace

P2iConfig P2iConfig::FromYamlString(const std::string& text, const std::string& source) {
  P2iConfig c;
  const YAML::Node root = LoadConfigMap(text, source);
  using Setter = std::function<void(const YAML::Node&)>;
  std::map<std::string, Setter> setters = {
      {"name", [&](const YAML::Node& n) { c.name = n.as<std::string>(); }},
      {"model", [&](const YAML::Node& n) { c.model = n.as<std::string>(); }},
      {"resolution", [&](const YAML::Node& n) { c.resolution = n.as<int>(); }},
      {"depth", [&](const YAML::Node& n) { c.depth = n.as<bool>(); }},
      {"g_schedule", [&](const YAML::Node& n) { c.g_schedule = n.as<std::string>(); }},
      {"g_min_width", [&](const YAML::Node& n) { c.g_min_width = n.as<int>(); }},
      {"g_max_width", [&](const YAML::Node& n) { c.g_max_width = n.as<int>(); }},
      {"g_widths", [&](const YAML::Node& n) { c.g_widths = n.as<std::vector<int>>(); }},
      {"g_fc_width", [&](const YAML::Node& n) { c.g_fc_width = n.as<int>(); }},
      {"g_norm", [&](const YAML::Node& n) { c.g_norm = n.as<std::string>(); }},
      {"pose_encoding", [&](const YAML::Node& n) { c.pose_encoding = n.as<std::string>(); }},
      {"fourier_bands", [&](const YAML::Node& n) { c.fourier_bands = FourierBands(n, source); }},
      {"recon_weight", [&](const YAML::Node& n) { c.recon_weight = n.as<double>(); }},
      {"r1_gamma", [&](const YAML::Node& n) { c.r1_gamma = n.as<double>(); }},
      {"densify_ratio", [&](const YAML::Node& n) { c.densify_ratio = n.as<double>(); }},
      {"densify_offset_m", [&](const YAML::Node& n) { c.densify_offset_m = n.as<double>(); }},
      {"densify_angle_deg", [&](const YAML::Node& n) { c.densify_angle_deg = n.as<double>(); }},
      {"densify_method", [&](const YAML::Node& n) { c.densify_method = n.as<std::string>(); }},
      {"densify_min_gap_m", [&](const YAML::Node& n) { c.densify_min_gap_m = n.as<double>(); }},
      {"densify_min_gap_deg", [&](const YAML::Node& n) { c.densify_min_gap_deg = n.as<double>(); }},
      {"densify_real_share", [&](const YAML::Node& n) { c.densify_real_share = n.as<double>(); }},
      {"densify_steps", [&](const YAML::Node& n) { c.densify_steps = n.as<int>(); }},
      {"d_base_width", [&](const YAML::Node& n) { c.d_base_width = n.as<int>(); }},
      {"d_max_width", [&](const YAML::Node& n) { c.d_max_width = n.as<int>(); }},
      {"latent_dim", [&](const YAML::Node& n) { c.latent_dim = n.as<int>(); }},
      {"mapping_width", [&](const YAML::Node& n) { c.mapping_width = n.as<int>(); }},
      {"attention", [&](const YAML::Node& n) { c.attention = n.as<bool>(); }},
      {"attention_max_res", [&](const YAML::Node& n) { c.attention_max_res = n.as<int>(); }},
      {"spectral_norm", [&](const YAML::Node& n) { c.spectral_norm = n.as<bool>(); }},
      {"sn_mappings", [&](const YAML::Node& n) { c.sn_mappings = n.as<bool>(); }},
      {"enet", [&](const YAML::Node& n) { c.enet = n.as<bool>(); }},
      {"enet_width", [&](const YAML::Node& n) { c.enet_width = n.as<int>(); }},
      {"enet_blocks", [&](const YAML::Node& n) { c.enet_blocks = n.as<int>(); }},
      {"hd", [&](const YAML::Node& n) { c.hd = n.as<bool>(); }},
      {"ld", [&](const YAML::Node& n) { c.ld = n.as<bool>(); }},
      {"k1", [&](const YAML::Node& n) { c.k1 = n.as<double>(); }},
      {"k2", [&](const YAML::Node& n) { c.k2 = n.as<double>(); }},
      {"k3", [&](const YAML::Node& n) { c.k3 = n.as<double>(); }},
      {"batch_size", [&](const YAML::Node& n) { c.batch_size = n.as<int>(); }},
      {"d_steps", [&](const YAML::Node& n) { c.d_steps = n.as<int>(); }},
      {"g_ema", [&](const YAML::Node& n) { c.g_ema = n.as<double>(); }},
      {"steps_phase1", [&](const YAML::Node& n) { c.steps_phase1 = n.as<int>(); }},
      {"steps_phase2", [&](const YAML::Node& n) { c.steps_phase2 = n.as<int>(); }},
      {"lr_g", [&](const YAML::Node& n) { c.lr_g = n.as<double>(); }},
      {"lr_d", [&](const YAML::Node& n) { c.lr_d = n.as<double>(); }},
      {"lr_enet", [&](const YAML::Node& n) { c.lr_enet = n.as<double>(); }},
      {"lr_decay_steps", [&](const YAML::Node& n) { c.lr_decay_steps = n.as<int>(); }},
      {"beta1", [&](const YAML::Node& n) { c.beta1 = n.as<double>(); }},
      {"beta2", [&](const YAML::Node& n) { c.beta2 = n.as<double>(); }},
      {"seed", [&](const YAML::Node& n) { c.seed = n.as<uint64_t>(); }},
      {"depth_max", [&](const YAML::Node& n) { c.depth_max = n.as<double>(); }},
      {"val_every", [&](const YAML::Node& n) { c.val_every = n.as<int>(); }},
      {"checkpoint_every", [&](const YAML::Node& n) { c.checkpoint_every = n.as<int>(); }},
      {"explode_factor", [&](const YAML::Node& n) { c.explode_factor = n.as<double>(); }},
  };
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    auto it = setters.find(key);
    if (it == setters.end())
      throw std::runtime_error("model config " + source + ": unknown key '" + key +
                               "' (see docs/MODEL.md for the keys)");
    try {
      it->second(kv.second);
    } catch (const YAML::Exception& e) {
      throw std::runtime_error("model config " + source + ": bad value for '" + key +
                               "': " + e.what());
    }
  }
  c.Validate();
  return c;
}

P2iConfig P2iConfig::FromYamlFile(const std::string& path) {
  return FromYamlString(ReadConfigText(path), path);
}

P2iConfig P2iConfig::FromYamlFile(const std::string& path,
                                  const std::vector<std::string>& overrides) {
  const std::string text = ReadConfigText(path);
  if (overrides.empty()) return FromYamlString(text, path);
  YAML::Node root = LoadConfigMap(text, path);
  std::string source = path + " with";
  for (const std::string& o : overrides) {
    const size_t eq = o.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == o.size())
      throw std::runtime_error("--set '" + o + "': expected KEY=VALUE with a model config key of " +
                               path + " (docs/MODEL.md), e.g. --set densify_ratio=3");
    try {
      root[o.substr(0, eq)] = YAML::Load(o.substr(eq + 1));
    } catch (const YAML::Exception& e) {
      throw std::runtime_error("--set '" + o + "': the value is not YAML: " + e.what());
    }
    source += " --set " + o;
  }
  YAML::Emitter e;
  e << root;
  return FromYamlString(e.c_str(), source);
}

std::string P2iConfig::ToYamlString() const {
  YAML::Emitter e;
  e << YAML::BeginMap;
  e << YAML::Key << "name" << YAML::Value << name;
  e << YAML::Key << "model" << YAML::Value << model;
  e << YAML::Key << "resolution" << YAML::Value << resolution;
  e << YAML::Key << "depth" << YAML::Value << depth;
  e << YAML::Key << "g_schedule" << YAML::Value << g_schedule;
  e << YAML::Key << "g_min_width" << YAML::Value << g_min_width;
  e << YAML::Key << "g_max_width" << YAML::Value << g_max_width;
  e << YAML::Key << "g_widths" << YAML::Value << YAML::Flow << g_widths;
  e << YAML::Key << "g_fc_width" << YAML::Value << g_fc_width;
  e << YAML::Key << "g_norm" << YAML::Value << g_norm;
  e << YAML::Key << "pose_encoding" << YAML::Value << pose_encoding;
  e << YAML::Key << "fourier_bands" << YAML::Value;
  if (fourier_bands == kAutoFourierBands)
    e << "auto";
  else
    e << fourier_bands;
  e << YAML::Key << "recon_weight" << YAML::Value << recon_weight;
  e << YAML::Key << "r1_gamma" << YAML::Value << r1_gamma;
  e << YAML::Key << "densify_ratio" << YAML::Value << densify_ratio;
  e << YAML::Key << "densify_offset_m" << YAML::Value << densify_offset_m;
  e << YAML::Key << "densify_angle_deg" << YAML::Value << densify_angle_deg;
  e << YAML::Key << "densify_method" << YAML::Value << densify_method;
  e << YAML::Key << "densify_min_gap_m" << YAML::Value << densify_min_gap_m;
  e << YAML::Key << "densify_min_gap_deg" << YAML::Value << densify_min_gap_deg;
  e << YAML::Key << "densify_real_share" << YAML::Value << densify_real_share;
  e << YAML::Key << "densify_steps" << YAML::Value << densify_steps;
  e << YAML::Key << "d_base_width" << YAML::Value << d_base_width;
  e << YAML::Key << "d_max_width" << YAML::Value << d_max_width;
  e << YAML::Key << "latent_dim" << YAML::Value << latent_dim;
  e << YAML::Key << "mapping_width" << YAML::Value << mapping_width;
  e << YAML::Key << "attention" << YAML::Value << attention;
  e << YAML::Key << "attention_max_res" << YAML::Value << attention_max_res;
  e << YAML::Key << "spectral_norm" << YAML::Value << spectral_norm;
  e << YAML::Key << "sn_mappings" << YAML::Value << sn_mappings;
  e << YAML::Key << "enet" << YAML::Value << enet;
  e << YAML::Key << "enet_width" << YAML::Value << enet_width;
  e << YAML::Key << "enet_blocks" << YAML::Value << enet_blocks;
  e << YAML::Key << "hd" << YAML::Value << hd;
  e << YAML::Key << "ld" << YAML::Value << ld;
  e << YAML::Key << "k1" << YAML::Value << k1;
  e << YAML::Key << "k2" << YAML::Value << k2;
  e << YAML::Key << "k3" << YAML::Value << k3;
  e << YAML::Key << "batch_size" << YAML::Value << batch_size;
  e << YAML::Key << "d_steps" << YAML::Value << d_steps;
  e << YAML::Key << "g_ema" << YAML::Value << g_ema;
  e << YAML::Key << "steps_phase1" << YAML::Value << steps_phase1;
  e << YAML::Key << "steps_phase2" << YAML::Value << steps_phase2;
  e << YAML::Key << "lr_g" << YAML::Value << lr_g;
  e << YAML::Key << "lr_d" << YAML::Value << lr_d;
  e << YAML::Key << "lr_enet" << YAML::Value << lr_enet;
  e << YAML::Key << "lr_decay_steps" << YAML::Value << lr_decay_steps;
  e << YAML::Key << "beta1" << YAML::Value << beta1;
  e << YAML::Key << "beta2" << YAML::Value << beta2;
  e << YAML::Key << "seed" << YAML::Value << seed;
  e << YAML::Key << "depth_max" << YAML::Value << depth_max;
  e << YAML::Key << "val_every" << YAML::Value << val_every;
  e << YAML::Key << "checkpoint_every" << YAML::Value << checkpoint_every;
  e << YAML::Key << "explode_factor" << YAML::Value << explode_factor;
  e << YAML::EndMap;
  return e.c_str();
}

}  // namespace p2i::model
