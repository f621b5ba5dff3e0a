/// @file refine_net.cc
/// @brief Refinement U-Net, its loss and its file (see refine_net.h).
#include "model/refine_net.h"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "model/checkpoint.h"

namespace p2i::model {

namespace F = torch::nn::functional;

void RefineNetOptions::Validate() const {
  if (in_channels < 1)
    throw std::invalid_argument("RefineNetOptions: in_channels must be >= 1 (set it from the "
                                "input layout), got " + std::to_string(in_channels));
  if (widths.empty() || widths.size() > 5)
    throw std::invalid_argument("RefineNetOptions: widths needs 1 to 5 levels, got " +
                                std::to_string(widths.size()));
  for (int w : widths)
    if (w < 1 || w > 512)
      throw std::invalid_argument("RefineNetOptions: every width must be in [1, 512], got " +
                                  std::to_string(w));
  if (!(depth_residual_m > 0) || !std::isfinite(depth_residual_m))
    throw std::invalid_argument("RefineNetOptions: depth_residual_m must be > 0");
}

void RefineTrainOptions::Validate() const {
  if (steps < 0) throw std::invalid_argument("RefineTrainOptions: steps must be >= 0");
  if (batch_size < 1) throw std::invalid_argument("RefineTrainOptions: batch_size must be >= 1");
  if (!(lr > 0) || !std::isfinite(lr))
    throw std::invalid_argument("RefineTrainOptions: lr must be > 0");
  if (!(ssim_weight >= 0 && ssim_weight <= 1))
    throw std::invalid_argument("RefineTrainOptions: ssim_weight must be in [0, 1]");
  if (!(depth_weight >= 0) || !std::isfinite(depth_weight))
    throw std::invalid_argument("RefineTrainOptions: depth_weight must be >= 0");
  if (crop < 0) throw std::invalid_argument("RefineTrainOptions: crop must be >= 0");
  if (threads < 1) throw std::invalid_argument("RefineTrainOptions: threads must be >= 1");
}

RefineBlockImpl::RefineBlockImpl(int in, int out) {
  a = register_module("a", torch::nn::Conv2d(torch::nn::Conv2dOptions(in, out, 3).padding(1)));
  b = register_module("b", torch::nn::Conv2d(torch::nn::Conv2dOptions(out, out, 3).padding(1)));
}

torch::Tensor RefineBlockImpl::forward(const torch::Tensor& x) {
  return torch::relu(b(torch::relu(a(x))));
}

RefineUNetImpl::RefineUNetImpl(const RefineNetOptions& options) : options_(options) {
  options_.Validate();
  const auto& w = options_.widths;
  const int levels = static_cast<int>(w.size());
  down = register_module("down", torch::nn::ModuleList());
  up = register_module("up", torch::nn::ModuleList());
  int in = options_.in_channels;
  for (int l = 0; l < levels; ++l) {
    down->push_back(RefineBlock(in, w[l]));
    in = w[l];
  }
  for (int l = levels - 2; l >= 0; --l) up->push_back(RefineBlock(w[l + 1] + w[l], w[l]));
  head = register_module("head", torch::nn::Conv2d(torch::nn::Conv2dOptions(w[0], 4, 3).padding(1)));
  // Zero head: the untrained net is the identity on the blend.
  torch::NoGradGuard no_grad;
  head->weight.zero_();
  head->bias.zero_();
}

torch::Tensor RefineUNetImpl::forward(const torch::Tensor& input, const torch::Tensor& base) {
  const int64_t h = input.size(2), w = input.size(3);
  const int m = options_.Multiple();
  const int64_t ph = (m - h % m) % m, pw = (m - w % m) % m;
  torch::Tensor x = input;
  if (ph || pw) x = F::pad(x, F::PadFuncOptions({0, pw, 0, ph}).mode(torch::kReplicate));
  const int levels = static_cast<int>(options_.widths.size());
  std::vector<torch::Tensor> skips;
  for (int l = 0; l < levels; ++l) {
    if (l > 0) x = F::avg_pool2d(x, F::AvgPool2dFuncOptions(2));
    x = down[l]->as<RefineBlockImpl>()->forward(x);
    skips.push_back(x);
  }
  for (int i = 0; i < levels - 1; ++i) {
    const torch::Tensor& skip = skips[levels - 2 - i];
    x = F::interpolate(x, F::InterpolateFuncOptions()
                              .size(std::vector<int64_t>{skip.size(2), skip.size(3)})
                              .mode(torch::kBilinear)
                              .align_corners(false));
    x = up[i]->as<RefineBlockImpl>()->forward(torch::cat({x, skip}, 1));
  }
  torch::Tensor r = head(x);
  if (ph || pw) r = r.slice(2, 0, h).slice(3, 0, w);
  const torch::Tensor rgb = torch::clamp(base.slice(1, 0, 3) + r.slice(1, 0, 3), 0.0, 1.0);
  const torch::Tensor depth =
      torch::relu(base.slice(1, 3, 4) + options_.depth_residual_m * r.slice(1, 3, 4));
  return torch::cat({rgb, depth}, 1);
}

double RefineUNetImpl::MacsPerPixel() const {
  const auto& w = options_.widths;
  double macs = 0.0, scale = 1.0;
  int in = options_.in_channels;
  for (size_t l = 0; l < w.size(); ++l) {
    macs += scale * 9.0 * (in * w[l] + w[l] * w[l]);
    in = w[l];
    scale /= 4.0;
  }
  scale = 1.0;
  for (size_t l = 0; l + 1 < w.size(); ++l) {
    macs += scale * 9.0 * ((w[l + 1] + w[l]) * w[l] + w[l] * w[l]);
    scale /= 4.0;
  }
  macs += 9.0 * w[0] * 4;
  return macs;
}

namespace {

// Mean over pixels where mask is set (mask broadcast over channels); 0 when none is.
torch::Tensor MaskedMean(const torch::Tensor& v, const torch::Tensor& mask) {
  const torch::Tensor m = mask.expand_as(v);
  return (v * m).sum() / m.sum().clamp_min(1.0);
}

torch::Tensor Dssim(const torch::Tensor& x, const torch::Tensor& y) {
  const auto pool = [](const torch::Tensor& t) {
    return F::avg_pool2d(F::pad(t, F::PadFuncOptions({1, 1, 1, 1}).mode(torch::kReflect)),
                         F::AvgPool2dFuncOptions(3).stride(1));
  };
  const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
  const torch::Tensor mx = pool(x), my = pool(y);
  const torch::Tensor sx = pool(x * x) - mx * mx, sy = pool(y * y) - my * my,
                      sxy = pool(x * y) - mx * my;
  const torch::Tensor ssim =
      ((2 * mx * my + c1) * (2 * sxy + c2)) / ((mx * mx + my * my + c1) * (sx + sy + c2));
  return torch::clamp((1 - ssim) / 2, 0, 1);
}

}  // namespace

RefineLossTerms RefineLoss(const torch::Tensor& out, const torch::Tensor& target,
                           const RefineTrainOptions& options) {
  RefineLossTerms t;
  const torch::Tensor orgb = out.slice(1, 0, 3), trgb = target.slice(1, 0, 3);
  const torch::Tensor td = target.slice(1, 3, 4);
  t.l1_rgb = (orgb - trgb).abs().mean();
  t.dssim = Dssim(orgb, trgb).mean();
  t.l1_depth = MaskedMean((out.slice(1, 3, 4) - td).abs(), (td > 0).to(torch::kFloat));
  const double w = options.ssim_weight;
  t.total = (1 - w) * t.l1_rgb + w * t.dssim + options.depth_weight * t.l1_depth;
  return t;
}

std::string RefineFileMeta::ToJson() const {
  nlohmann::json j;
  j["kind"] = "p2i_refine";
  j["format_version"] = format_version;
  j["in_channels"] = net.in_channels;
  j["widths"] = net.widths;
  j["depth_residual_m"] = net.depth_residual_m;
  j["layout"] = layout;
  j["steps"] = steps;
  j["trained_on"] = trained_on;
  return j.dump(2);
}

RefineFileMeta RefineFileMeta::FromJson(const std::string& text, const std::string& source) {
  RefineFileMeta m;
  try {
    const auto j = nlohmann::json::parse(text);
    if (j.value("kind", std::string()) != "p2i_refine")
      throw std::runtime_error("refinement file " + source +
                               ": not a refinement network (kind is not p2i_refine)");
    m.format_version = j.at("format_version").get<int>();
    if (m.format_version != 1)
      throw std::runtime_error("refinement file " + source + " has format version " +
                               std::to_string(m.format_version) +
                               " but this build reads version 1: retrain it with this build");
    m.net.in_channels = j.at("in_channels").get<int>();
    m.net.widths = j.at("widths").get<std::vector<int>>();
    m.net.depth_residual_m = j.at("depth_residual_m").get<double>();
    m.layout = j.at("layout").get<std::string>();
    m.steps = j.at("steps").get<int64_t>();
    m.trained_on = j.value("trained_on", std::string());
    m.net.Validate();
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("refinement file " + source + ": bad metadata: " + e.what());
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("refinement file " + source + ": " + e.what());
  }
  return m;
}

void SaveRefineNet(const std::string& path, const RefineFileMeta& meta, RefineUNet& net,
                   torch::optim::Adam* optimizer) {
  torch::serialize::OutputArchive archive;
  archive.write("meta", c10::IValue(meta.ToJson()));
  torch::serialize::OutputArchive weights;
  net->save(weights);
  archive.write("net", weights);
  if (optimizer) {
    torch::serialize::OutputArchive opt;
    optimizer->save(opt);
    archive.write("adam", opt);
  }
  WriteFileAtomically(path, [&](const std::string& temp) {
    try {
      archive.save_to(temp);
    } catch (const c10::Error& e) {
      throw std::runtime_error("cannot write refinement file " + temp + ": " +
                               e.what_without_backtrace());
    }
  });
}

namespace {

torch::serialize::InputArchive OpenRefineArchive(const std::string& path, RefineFileMeta* meta) {
  if (!std::filesystem::exists(path))
    throw std::runtime_error("refinement file " + path + " does not exist");
  torch::serialize::InputArchive archive;
  c10::IValue meta_value;
  try {
    archive.load_from(path);
    if (!archive.try_read("meta", meta_value))
      throw std::runtime_error("refinement file " + path + " has no metadata: not a p2i file");
  } catch (const c10::Error& e) {
    throw std::runtime_error("cannot read refinement file " + path + ": " +
                             e.what_without_backtrace());
  }
  *meta = RefineFileMeta::FromJson(meta_value.toStringRef(), path);
  return archive;
}

}  // namespace

RefineFileMeta ReadRefineMeta(const std::string& path) {
  RefineFileMeta meta;
  OpenRefineArchive(path, &meta);
  return meta;
}

RefineUNet LoadRefineNet(const std::string& path, RefineFileMeta* meta_out) {
  RefineFileMeta meta;
  torch::serialize::InputArchive archive = OpenRefineArchive(path, &meta);
  RefineUNet net(meta.net);
  try {
    torch::serialize::InputArchive weights;
    if (!archive.try_read("net", weights))
      throw std::runtime_error("refinement file " + path + " has no weights ('net')");
    net->load(weights);
  } catch (const c10::Error& e) {
    throw std::runtime_error("cannot load refinement file " + path + ": " +
                             e.what_without_backtrace());
  }
  if (meta_out) *meta_out = meta;
  return net;
}

bool LoadRefineOptimizer(const std::string& path, torch::optim::Adam& optimizer) {
  RefineFileMeta meta;
  torch::serialize::InputArchive archive = OpenRefineArchive(path, &meta);
  torch::serialize::InputArchive opt;
  try {
    if (!archive.try_read("adam", opt)) return false;
    optimizer.load(opt);
  } catch (const c10::Error& e) {
    throw std::runtime_error("cannot load the optimiser state of " + path + ": " +
                             e.what_without_backtrace());
  }
  return true;
}

}  // namespace p2i::model
