/// @file refiner_test.cc
/// @brief The torch-free Refiner: identity when fresh, fitting a correction the inputs reveal
/// (loss falls, refined beats the blend), save/load/clone, layout and plane-count refusals.
#include <catch2/catch.hpp>

#include <filesystem>
#include <random>

#include <opencv2/imgproc.hpp>

#include "model/refiner.h"
#include "tests/model/model_test_util.h"

using namespace p2i::model;

namespace {

// A target with texture; the blend is darker (an exposure error) and has a missing band the
// confidence plane marks; planes: the blend's 3 colours and the confidence.
RefineSample Sample(int seed, int h = 24, int w = 32) {
  cv::RNG rng(seed);
  RefineSample s;
  s.target_rgb.create(h, w, CV_8UC3);
  rng.fill(s.target_rgb, cv::RNG::UNIFORM, 40, 220);
  cv::GaussianBlur(s.target_rgb, s.target_rgb, cv::Size(3, 3), 0);
  s.target_depth = cv::Mat(h, w, CV_32FC1, cv::Scalar(2.0f));
  cv::Mat t;
  s.target_rgb.convertTo(t, CV_32FC3, 1.0 / 255.0);
  s.input.base_rgb = t * 0.75;
  s.input.base_depth = cv::Mat(h, w, CV_32FC1, cv::Scalar(2.1f));
  std::vector<cv::Mat> ch;
  cv::split(s.input.base_rgb, ch);
  ch.push_back(cv::Mat(h, w, CV_32FC1, cv::Scalar(1.0f)));  // a confidence plane
  for (auto& c : ch) s.input.planes.insert(s.input.planes.end(), c.begin<float>(), c.end<float>());
  s.input.channels = 4;
  return s;
}

RefineNetOptions Net() {
  RefineNetOptions o;
  o.in_channels = 4;
  o.widths = {8, 16};
  return o;
}

}  // namespace

TEST_CASE("A fresh Refiner returns the blend", "[unit]") {
  Refiner r(Net(), "test");
  const RefineSample s = Sample(1);
  cv::Mat rgb, depth, blend8;
  r.Refine(s.input, &rgb, &depth);
  s.input.base_rgb.convertTo(blend8, CV_8UC3, 255.0);
  CHECK(cv::norm(rgb, blend8, cv::NORM_INF) <= 1.0);
  CHECK(cv::norm(depth, s.input.base_depth, cv::NORM_INF) < 1e-6);
  CHECK(r.ParameterCount() > 0);
}

TEST_CASE("Refiner::Fit lowers the loss and the refined view beats the blend", "[unit]") {
  std::vector<RefineSample> train, test;
  for (int i = 0; i < 6; ++i) train.push_back(Sample(i));
  for (int i = 10; i < 12; ++i) test.push_back(Sample(i));
  Refiner r(Net(), "test");
  const RefineEval before = r.Evaluate(test);
  RefineTrainOptions o;
  o.steps = 120;
  o.batch_size = 2;
  o.lr = 3e-3;
  const RefineFitReport fit = r.Fit(train, o);
  CHECK(fit.steps == 120);
  CHECK(fit.last_loss < 0.6 * fit.first_loss);
  const RefineEval after = r.Evaluate(test);
  INFO("blend " << after.psnr_blend << " dB, refined " << after.psnr_refined << " dB");
  CHECK(before.psnr_refined == Approx(before.psnr_blend).margin(0.05));
  CHECK(after.psnr_refined > after.psnr_blend + 1.0);

  // Save, load, clone: same output.
  const std::string dir = testing::TempDir("refiner");
  r.Save(dir + "/r.pt", "unit test", /*with_optimizer=*/true);
  auto loaded = Refiner::Load(dir + "/r.pt", "test");
  CHECK(loaded->total_steps() == 120);
  auto clone = r.Clone();
  cv::Mat a, ad, b, bd, c, cd;
  r.Refine(test[0].input, &a, &ad);
  loaded->Refine(test[0].input, &b, &bd);
  clone->Refine(test[0].input, &c, &cd);
  CHECK(cv::norm(a, b, cv::NORM_INF) == 0);
  CHECK(cv::norm(a, c, cv::NORM_INF) == 0);
  // A loaded net continues training from its Adam state.
  o.steps = 5;
  CHECK(loaded->Fit(train, o).total_steps == 125);
  CHECK_THROWS_WITH(Refiner::Load(dir + "/r.pt", "other_layout"), Catch::Contains("other_layout"));

  RefineSample wrong = Sample(3);
  wrong.input.planes.resize(wrong.input.planes.size() * 3 / 4);
  wrong.input.channels = 3;
  CHECK_THROWS_WITH(r.Refine(wrong.input, &a, &ad), Catch::Contains("planes"));
  std::filesystem::remove_all(dir);
}
