/// @file lpips.cc
/// @brief LPIPS-Squeeze with LibTorch functional ops on the tensors of the shared state dict.
#include "model/lpips.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <stdexcept>

#include <torch/script.h>
#include <torch/torch.h>

namespace p2i::model {
namespace {

namespace F = torch::nn::functional;

/// Output channels of the 7 SqueezeNet slices that LPIPS compares.
constexpr int kLayerChannels[7] = {64, 128, 256, 384, 384, 512, 512};

struct Conv {
  torch::Tensor weight;
  torch::Tensor bias;
};

struct Fire {
  Conv squeeze;
  Conv expand1x1;
  Conv expand3x3;
};

torch::Tensor Get(const std::map<std::string, torch::Tensor>& dict, const std::string& key,
                  const std::string& file) {
  auto it = dict.find(key);
  if (it == dict.end()) {
    throw std::runtime_error("LPIPS-Squeeze weights " + file + ": missing tensor '" + key +
                             "' (expected the lpips package's SqueezeNet layout; see "
                             "../shared/models/lpips/README.md)");
  }
  return it->second;
}

Conv GetConv(const std::map<std::string, torch::Tensor>& dict, const std::string& prefix,
             const std::string& file) {
  return {Get(dict, prefix + ".weight", file), Get(dict, prefix + ".bias", file)};
}

Fire GetFire(const std::map<std::string, torch::Tensor>& dict, const std::string& prefix,
             const std::string& file) {
  return {GetConv(dict, prefix + ".squeeze", file), GetConv(dict, prefix + ".expand1x1", file),
          GetConv(dict, prefix + ".expand3x3", file)};
}

torch::Tensor RunConv(const torch::Tensor& x, const Conv& c, int stride, int padding) {
  return torch::conv2d(x, c.weight, c.bias, stride, padding);
}

torch::Tensor RunFire(const torch::Tensor& x, const Fire& f) {
  torch::Tensor s = torch::relu(RunConv(x, f.squeeze, 1, 0));
  return torch::cat({torch::relu(RunConv(s, f.expand1x1, 1, 0)),
                     torch::relu(RunConv(s, f.expand3x3, 1, 1))},
                    1);
}

torch::Tensor MaxPool(const torch::Tensor& x) {
  return torch::max_pool2d(x, {3, 3}, {2, 2}, {0, 0}, {1, 1}, /*ceil_mode=*/true);
}

/// N x 3 x H x W float tensor in [-1, 1] from RGB images of one size.
torch::Tensor ToTensor(const std::vector<const cv::Mat*>& images) {
  const int h = images.front()->rows;
  const int w = images.front()->cols;
  torch::Tensor out = torch::empty({static_cast<int64_t>(images.size()), 3, h, w});
  for (size_t i = 0; i < images.size(); ++i) {
    const cv::Mat& img = *images[i];
    cv::Mat f;
    switch (img.depth()) {
      case CV_8U:
        img.convertTo(f, CV_32F, 2.0 / 255.0, -1.0);
        break;
      case CV_32F:
      case CV_64F:
        img.convertTo(f, CV_32F, 2.0, -1.0);
        break;
      default:
        throw std::invalid_argument(
            "LpipsSqueeze: images must be CV_8UC3 or float RGB in [0, 1]");
    }
    if (!f.isContinuous()) f = f.clone();
    torch::Tensor hwc = torch::from_blob(f.data, {h, w, 3}, torch::kFloat32);
    out[static_cast<int64_t>(i)].copy_(hwc.permute({2, 0, 1}));
  }
  return out;
}

void CheckImage(const cv::Mat& img) {
  if (img.empty() || img.channels() != 3) {
    throw std::invalid_argument("LpipsSqueeze: expected a non-empty 3-channel RGB image");
  }
  if (img.rows < 16 || img.cols < 16) {
    throw std::invalid_argument("LpipsSqueeze: images must be at least 16x16, got " +
                                std::to_string(img.cols) + "x" + std::to_string(img.rows));
  }
}

}  // namespace

struct LpipsSqueeze::Impl {
  Conv conv1;
  std::vector<Fire> fires;  // Fire 3, 4, 6, 7, 9, 10, 11, 12 of torchvision's features
  std::vector<torch::Tensor> lin;  // 7 x [1, C, 1, 1]
  torch::Tensor shift = torch::tensor({-0.030f, -0.088f, -0.188f}).view({1, 3, 1, 1});
  torch::Tensor scale = torch::tensor({0.458f, 0.448f, 0.450f}).view({1, 3, 1, 1});

  /// The 7 feature maps, each normalised over channels.
  std::vector<torch::Tensor> Features(torch::Tensor x) const {
    x = (x - shift) / scale;
    std::vector<torch::Tensor> out;
    x = torch::relu(RunConv(x, conv1, 2, 0));  // slice1
    out.push_back(x);
    x = RunFire(RunFire(MaxPool(x), fires[0]), fires[1]);  // slice2
    out.push_back(x);
    x = RunFire(RunFire(MaxPool(x), fires[2]), fires[3]);  // slice3
    out.push_back(x);
    x = RunFire(MaxPool(x), fires[4]);  // slice4
    out.push_back(x);
    x = RunFire(x, fires[5]);  // slice5
    out.push_back(x);
    x = RunFire(x, fires[6]);  // slice6
    out.push_back(x);
    x = RunFire(x, fires[7]);  // slice7
    out.push_back(x);
    for (auto& f : out) {
      f = f / (torch::sqrt(torch::sum(f * f, 1, /*keepdim=*/true)) + 1e-10);
    }
    return out;
  }

  /// Distances for N pairs, in0/in1 N x 3 x H x W in [-1, 1].
  torch::Tensor Forward(const torch::Tensor& in0, const torch::Tensor& in1) const {
    const auto f0 = Features(in0);
    const auto f1 = Features(in1);
    torch::Tensor total = torch::zeros({in0.size(0)});
    for (size_t k = 0; k < f0.size(); ++k) {
      torch::Tensor d = (f0[k] - f1[k]).pow(2);
      torch::Tensor l = torch::conv2d(d, lin[k]);  // N x 1 x h x w
      total = total + l.mean({1, 2, 3});
    }
    return total;
  }
};

LpipsSqueeze::LpipsSqueeze(const std::string& weights_path)
    : impl_(std::make_unique<Impl>()), weights_path_(weights_path) {
  std::ifstream in(weights_path, std::ios::binary);
  if (!in) {
    throw std::runtime_error("LPIPS-Squeeze: cannot open weights file '" + weights_path +
                             "' (" + kLpipsUnavailableMessage + ")");
  }
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::map<std::string, torch::Tensor> dict;
  try {
    const c10::Dict<c10::IValue, c10::IValue> generic = torch::pickle_load(bytes).toGenericDict();
    for (const auto& entry : generic) {
      dict[entry.key().toStringRef()] = entry.value().toTensor().to(torch::kFloat32).contiguous();
    }
  } catch (const c10::Error& e) {
    throw std::runtime_error("LPIPS-Squeeze: cannot parse weights file '" + weights_path +
                             "' as a PyTorch state dict: " + e.what_without_backtrace());
  }
  Impl& m = *impl_;
  m.conv1 = GetConv(dict, "net.slice1.0", weights_path);
  const std::pair<int, int> fire_keys[8] = {{2, 3}, {2, 4}, {3, 6}, {3, 7},
                                            {4, 9}, {5, 10}, {6, 11}, {7, 12}};
  for (const auto& [slice, index] : fire_keys) {
    m.fires.push_back(GetFire(
        dict, "net.slice" + std::to_string(slice) + "." + std::to_string(index), weights_path));
  }
  for (int k = 0; k < 7; ++k) {
    const std::string key = "lin" + std::to_string(k) + ".model.1.weight";
    torch::Tensor w = Get(dict, key, weights_path);
    if (w.dim() != 4 || w.size(0) != 1 || w.size(1) != kLayerChannels[k]) {
      throw std::runtime_error("LPIPS-Squeeze weights " + weights_path + ": tensor '" + key +
                               "' has the wrong shape (expected [1, " +
                               std::to_string(kLayerChannels[k]) + ", 1, 1])");
    }
    m.lin.push_back(w);
  }
  if (m.conv1.weight.sizes() != torch::IntArrayRef({64, 3, 3, 3})) {
    throw std::runtime_error("LPIPS-Squeeze weights " + weights_path +
                             ": 'net.slice1.0.weight' is not 64x3x3x3 (not SqueezeNet 1.1?)");
  }
}

LpipsSqueeze::~LpipsSqueeze() = default;

std::string LpipsSqueeze::ResolveWeightsPath(const std::string& path_option) {
  if (!path_option.empty()) return path_option;
  const char* env = std::getenv("P2I_LPIPS_WEIGHTS");
  if (env != nullptr && env[0] != '\0') return env;
  return "";
}

std::unique_ptr<LpipsSqueeze> LpipsSqueeze::TryLoad(const std::string& path_option,
                                                    std::string* why) {
  const std::string path = ResolveWeightsPath(path_option);
  std::error_code ec;
  if (path.empty() || !std::filesystem::is_regular_file(path, ec)) {
    if (why != nullptr) {
      *why = std::string(kLpipsUnavailableMessage) +
             (path.empty() ? " (no path given)" : " (file not found: " + path + ")");
    }
    return nullptr;
  }
  return std::make_unique<LpipsSqueeze>(path);
}

double LpipsSqueeze::Distance(const cv::Mat& a, const cv::Mat& b) const {
  return DistanceBatch({a}, {b}).front();
}

std::vector<double> LpipsSqueeze::DistanceBatch(const std::vector<cv::Mat>& a,
                                                const std::vector<cv::Mat>& b) const {
  if (a.size() != b.size()) {
    throw std::invalid_argument("LpipsSqueeze::DistanceBatch: lists differ in length");
  }
  // Group pair indices by image size so that each group is one batched forward pass.
  std::map<std::pair<int, int>, std::vector<size_t>> groups;
  for (size_t i = 0; i < a.size(); ++i) {
    CheckImage(a[i]);
    CheckImage(b[i]);
    if (a[i].size() != b[i].size()) {
      throw std::invalid_argument("LpipsSqueeze: pair " + std::to_string(i) +
                                  " has images of different sizes");
    }
    groups[{a[i].rows, a[i].cols}].push_back(i);
  }
  std::vector<double> out(a.size(), 0.0);
  torch::NoGradGuard no_grad;
  for (const auto& [size, indices] : groups) {
    std::vector<const cv::Mat*> pa, pb;
    for (size_t i : indices) {
      pa.push_back(&a[i]);
      pb.push_back(&b[i]);
    }
    const torch::Tensor d = impl_->Forward(ToTensor(pa), ToTensor(pb)).to(torch::kFloat64);
    for (size_t j = 0; j < indices.size(); ++j) {
      out[indices[j]] = d[static_cast<int64_t>(j)].item<double>();
    }
  }
  return out;
}

std::optional<double> LpipsSqueezeOrMissing(const LpipsSqueeze* metric, const cv::Mat& a,
                                            const cv::Mat& b) {
  if (metric == nullptr) return std::nullopt;
  return metric->Distance(a, b);
}

}  // namespace p2i::model
