/// @file refiner.cc
/// @brief Refiner: the torch-free face of the refinement U-Net (see refiner.h).
#include "model/refiner.h"

#include <algorithm>
#include <numeric>
#include <random>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "model/metrics.h"
#include "model/refine_net.h"

namespace p2i::model {

namespace {

// C x H x W float tensor from the packed planes (copies).
torch::Tensor InputTensor(const RefineInput& in) {
  const int64_t h = in.base_rgb.rows, w = in.base_rgb.cols;
  if (in.channels < 1 || static_cast<int64_t>(in.planes.size()) != in.channels * h * w)
    throw std::invalid_argument("refinement input: " + std::to_string(in.planes.size()) +
                                " floats are not " + std::to_string(in.channels) +
                                " planes of the blend's size " + std::to_string(w) + "x" +
                                std::to_string(h));
  return torch::from_blob(const_cast<float*>(in.planes.data()), {in.channels, h, w}).clone();
}

// 4 x H x W: rgb [0, 1] + depth (m).
torch::Tensor RgbdTensor(const cv::Mat& rgb, const cv::Mat& depth) {
  const int h = rgb.rows, w = rgb.cols;
  cv::Mat rgbf;
  if (rgb.type() == CV_8UC3)
    rgb.convertTo(rgbf, CV_32FC3, 1.0 / 255.0);
  else if (rgb.type() == CV_32FC3)
    rgbf = rgb;
  else
    throw std::invalid_argument("refinement: rgb must be CV_8UC3 or CV_32FC3");
  if (depth.type() != CV_32FC1 || depth.rows != h || depth.cols != w)
    throw std::invalid_argument("refinement: depth must be CV_32FC1 of the rgb's size");
  torch::Tensor t = torch::empty({4, h, w});
  std::vector<cv::Mat> ch(3);
  for (int c = 0; c < 3; ++c) ch[c] = cv::Mat(h, w, CV_32FC1, t[c].data_ptr<float>());
  cv::split(rgbf, ch.data());
  cv::Mat d(h, w, CV_32FC1, t[3].data_ptr<float>());
  depth.copyTo(d);
  cv::patchNaNs(d, 0.0);
  return t;
}

void ToMats(const torch::Tensor& out, cv::Mat* rgb, cv::Mat* depth) {
  const torch::Tensor o = out.contiguous();
  const int h = static_cast<int>(o.size(1)), w = static_cast<int>(o.size(2));
  std::vector<cv::Mat> ch(3);
  for (int c = 0; c < 3; ++c)
    ch[c] = cv::Mat(h, w, CV_32FC1, o[c].data_ptr<float>());
  cv::Mat rgbf;
  cv::merge(ch, rgbf);
  rgbf.convertTo(*rgb, CV_8UC3, 255.0);
  cv::Mat(h, w, CV_32FC1, o[3].data_ptr<float>()).copyTo(*depth);
}

}  // namespace

struct Refiner::Impl {
  RefineNetOptions options;
  std::string layout;
  RefineUNet net{nullptr};
  std::unique_ptr<torch::optim::Adam> adam;
  double adam_lr = 0.0;
  int64_t steps = 0;
  std::string path;  // the file loaded from (for the Adam state), "" when fresh
  std::mt19937_64 rng{1};

  // Samples as tensors (input, base, target), cached by address of the sample vector content.
  struct Cached {
    torch::Tensor input, base, target;
  };
  std::vector<Cached> Prepare(const std::vector<RefineSample>& samples) {
    std::vector<Cached> out;
    out.reserve(samples.size());
    for (const auto& s : samples) {
      Cached c;
      c.input = InputTensor(s.input);
      if (c.input.size(0) != options.in_channels)
        throw std::invalid_argument("refinement sample has " + std::to_string(c.input.size(0)) +
                                    " input planes, the net takes " +
                                    std::to_string(options.in_channels));
      c.base = RgbdTensor(s.input.base_rgb, s.input.base_depth);
      c.target = RgbdTensor(s.target_rgb, s.target_depth);
      out.push_back(std::move(c));
    }
    return out;
  }
};

Refiner::Refiner() : impl_(std::make_unique<Impl>()) {}

Refiner::Refiner(const RefineNetOptions& net, const std::string& layout)
    : impl_(std::make_unique<Impl>()) {
  net.Validate();
  impl_->options = net;
  impl_->layout = layout;
  impl_->net = RefineUNet(net);
  impl_->net->eval();
}

Refiner::~Refiner() = default;

std::unique_ptr<Refiner> Refiner::Load(const std::string& path, const std::string& expected_layout) {
  RefineFileMeta meta;
  RefineUNet net = LoadRefineNet(path, &meta);
  if (!expected_layout.empty() && meta.layout != expected_layout)
    throw std::runtime_error("refinement file " + path + " was trained on input layout '" +
                             meta.layout + "' but this build feeds '" + expected_layout +
                             "': retrain it (docs/FUSION.md) or use the matching build");
  std::unique_ptr<Refiner> r(new Refiner());
  r->impl_->options = meta.net;
  r->impl_->layout = meta.layout;
  r->impl_->net = net;
  r->impl_->net->eval();
  r->impl_->steps = meta.steps;
  r->impl_->path = path;
  return r;
}

std::unique_ptr<Refiner> Refiner::Clone() const {
  std::unique_ptr<Refiner> r(new Refiner());
  r->impl_->options = impl_->options;
  r->impl_->layout = impl_->layout;
  r->impl_->net = RefineUNet(impl_->options);
  {
    torch::NoGradGuard g;
    auto from = impl_->net->named_parameters();
    for (auto& kv : r->impl_->net->named_parameters()) kv.value().copy_(from[kv.key()]);
  }
  r->impl_->net->eval();
  r->impl_->steps = impl_->steps;
  return r;
}

void Refiner::Refine(const RefineInput& input, cv::Mat* rgb, cv::Mat* depth) {
  torch::InferenceMode guard;
  const torch::Tensor x = InputTensor(input).unsqueeze(0);
  const torch::Tensor base = RgbdTensor(input.base_rgb, input.base_depth).unsqueeze(0);
  if (x.size(1) != impl_->options.in_channels)
    throw std::invalid_argument("refinement input has " + std::to_string(x.size(1)) +
                                " planes, the net takes " +
                                std::to_string(impl_->options.in_channels));
  ToMats(impl_->net->forward(x, base)[0], rgb, depth);
}

RefineFitReport Refiner::Fit(const std::vector<RefineSample>& samples,
                             const RefineTrainOptions& options,
                             const std::function<bool()>& should_stop) {
  options.Validate();
  RefineFitReport report;
  report.total_steps = impl_->steps;
  if (samples.empty() || options.steps == 0) return report;
  torch::set_num_threads(options.threads);
  std::vector<Impl::Cached> data = impl_->Prepare(samples);
  impl_->net->train();
  if (!impl_->adam || impl_->adam_lr != options.lr) {
    impl_->adam = std::make_unique<torch::optim::Adam>(impl_->net->parameters(),
                                                       torch::optim::AdamOptions(options.lr));
    impl_->adam_lr = options.lr;
    if (!impl_->path.empty()) LoadRefineOptimizer(impl_->path, *impl_->adam);
  }
  impl_->rng.seed(options.seed + static_cast<uint64_t>(impl_->steps));
  const int m = impl_->options.Multiple();
  std::vector<double> losses;
  for (int step = 0; step < options.steps; ++step) {
    if (should_stop && should_stop()) {
      report.stopped = true;
      break;
    }
    std::vector<torch::Tensor> xs, bs, ts;
    for (int b = 0; b < options.batch_size; ++b) {
      const auto& c = data[impl_->rng() % data.size()];
      torch::Tensor x = c.input, base = c.base, t = c.target;
      const int64_t h = x.size(1), w = x.size(2);
      if (options.crop > 0 && options.crop < std::min(h, w)) {
        const int crop = std::max(m, options.crop / m * m);
        const int64_t y0 = static_cast<int64_t>(impl_->rng() % static_cast<uint64_t>(h - crop + 1));
        const int64_t x0 = static_cast<int64_t>(impl_->rng() % static_cast<uint64_t>(w - crop + 1));
        x = x.slice(1, y0, y0 + crop).slice(2, x0, x0 + crop);
        base = base.slice(1, y0, y0 + crop).slice(2, x0, x0 + crop);
        t = t.slice(1, y0, y0 + crop).slice(2, x0, x0 + crop);
      }
      if (impl_->rng() % 2) {  // horizontal flip: the net sees no absolute image position
        x = x.flip({2});
        base = base.flip({2});
        t = t.flip({2});
      }
      xs.push_back(x);
      bs.push_back(base);
      ts.push_back(t);
    }
    impl_->adam->zero_grad();
    const torch::Tensor out = impl_->net->forward(torch::stack(xs), torch::stack(bs));
    const RefineLossTerms loss = RefineLoss(out, torch::stack(ts), options);
    loss.total.backward();
    impl_->adam->step();
    losses.push_back(loss.total.item<double>());
    ++impl_->steps;
    ++report.steps;
  }
  impl_->net->eval();
  report.total_steps = impl_->steps;
  if (!losses.empty()) {
    const size_t n = std::min<size_t>(10, losses.size());
    report.first_loss = std::accumulate(losses.begin(), losses.begin() + n, 0.0) / n;
    report.last_loss = std::accumulate(losses.end() - n, losses.end(), 0.0) / n;
  }
  return report;
}

RefineEval Refiner::Evaluate(const std::vector<RefineSample>& samples) {
  RefineEval e;
  for (const auto& s : samples) {
    cv::Mat rgb, depth, blend8;
    Refine(s.input, &rgb, &depth);
    s.input.base_rgb.convertTo(blend8, CV_8UC3, 255.0);
    e.psnr_refined += Psnr(rgb, s.target_rgb);
    e.psnr_blend += Psnr(blend8, s.target_rgb);
    e.ssim_refined += Ssim(rgb, s.target_rgb);
    e.ssim_blend += Ssim(blend8, s.target_rgb);
    ++e.views;
  }
  if (e.views > 0) {
    e.psnr_refined /= e.views;
    e.psnr_blend /= e.views;
    e.ssim_refined /= e.views;
    e.ssim_blend /= e.views;
  }
  return e;
}

void Refiner::Save(const std::string& path, const std::string& trained_on, bool with_optimizer) {
  RefineFileMeta meta;
  meta.net = impl_->options;
  meta.layout = impl_->layout;
  meta.steps = impl_->steps;
  meta.trained_on = trained_on;
  SaveRefineNet(path, meta, impl_->net, with_optimizer ? impl_->adam.get() : nullptr);
}

const RefineNetOptions& Refiner::net_options() const { return impl_->options; }
const std::string& Refiner::layout() const { return impl_->layout; }
int64_t Refiner::total_steps() const { return impl_->steps; }
int64_t Refiner::ParameterCount() const {
  int64_t n = 0;
  for (const auto& p : impl_->net->parameters()) n += p.numel();
  return n;
}
double Refiner::MacsPerPixel() const { return impl_->net->MacsPerPixel(); }

}  // namespace p2i::model
