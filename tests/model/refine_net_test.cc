/// @file refine_net_test.cc
/// @brief The refinement U-Net: identity on the blend when untrained, shapes at sizes that are
/// not multiples of its levels, its loss, learning a simple correction, and its file.
#include <catch2/catch.hpp>
#include <torch/torch.h>

#include <filesystem>
#include <fstream>

#include "model/refine_net.h"
#include "tests/model/model_test_util.h"

using namespace p2i::model;

namespace {

RefineNetOptions Small(int in) {
  RefineNetOptions o;
  o.in_channels = in;
  o.widths = {8, 16};
  return o;
}

}  // namespace

TEST_CASE("An untrained refinement net returns the blend, at any size", "[unit]") {
  torch::manual_seed(3);
  RefineUNet net(Small(5));
  for (auto hw : {std::pair<int, int>{16, 16}, {15, 21}, {24, 32}}) {
    const torch::Tensor in = torch::rand({2, 5, hw.first, hw.second});
    torch::Tensor base = torch::rand({2, 4, hw.first, hw.second});
    const torch::Tensor out = net->forward(in, base);
    REQUIRE(out.sizes() == base.sizes());
    CHECK(torch::allclose(out, base));
  }
  CHECK(net->MacsPerPixel() > 0);
}

TEST_CASE("Refinement options are validated", "[unit]") {
  RefineNetOptions o;
  CHECK_THROWS_AS(o.Validate(), std::invalid_argument);  // in_channels unset
  o.in_channels = 3;
  o.Validate();
  o.widths = {};
  CHECK_THROWS_AS(o.Validate(), std::invalid_argument);
  RefineTrainOptions t;
  t.Validate();
  t.ssim_weight = 2;
  CHECK_THROWS_AS(t.Validate(), std::invalid_argument);
}

TEST_CASE("The refinement loss is zero on the target and counts depth only where it is valid",
          "[unit]") {
  RefineTrainOptions o;
  torch::Tensor target = torch::rand({1, 4, 8, 8});
  target.slice(1, 3, 4).slice(2, 0, 4).zero_();  // top half without depth
  auto same = RefineLoss(target.clone(), target, o);
  CHECK(same.total.item<float>() < 1e-6f);
  torch::Tensor out = target.clone();
  out.slice(1, 3, 4).slice(2, 0, 4).fill_(9.0);  // wrong only where the target has no depth
  CHECK(RefineLoss(out, target, o).l1_depth.item<float>() < 1e-6f);
  out.slice(1, 3, 4).slice(2, 4, 8).add_(1.0);
  CHECK(RefineLoss(out, target, o).l1_depth.item<float>() == Approx(1.0).epsilon(1e-4));
  out = target.clone();
  out.slice(1, 0, 3).add_(0.1);
  auto off = RefineLoss(out, target, o);
  CHECK(off.l1_rgb.item<float>() > 0.05f);
}

TEST_CASE("The refinement net learns a colour and depth correction of the blend", "[unit]") {
  // The blend is the target with a gain error and a depth offset the input channels reveal.
  torch::manual_seed(1);
  RefineNetOptions o = Small(4);
  RefineUNet net(o);
  RefineTrainOptions t;
  torch::optim::Adam opt(net->parameters(), torch::optim::AdamOptions(3e-3));
  const torch::Tensor target = torch::rand({4, 4, 16, 16}) * 0.8 + 0.1;
  torch::Tensor base = target.clone();
  base.slice(1, 0, 3).mul_(0.7);
  base.slice(1, 3, 4).add_(0.1);
  const torch::Tensor input = base.clone();
  const float before = RefineLoss(net->forward(input, base), target, t).total.item<float>();
  float after = before;
  for (int i = 0; i < 150; ++i) {
    opt.zero_grad();
    auto loss = RefineLoss(net->forward(input, base), target, t).total;
    loss.backward();
    opt.step();
    after = loss.item<float>();
  }
  INFO("loss before " << before << " after " << after);
  CHECK(after < 0.5f * before);
}

TEST_CASE("A refinement file round-trips weights and metadata and refuses other files",
          "[unit]") {
  const std::string dir = testing::TempDir("refine_file");
  torch::manual_seed(2);
  RefineUNet net(Small(6));
  {
    torch::NoGradGuard g;
    net->head->weight.normal_();  // not the zero start
  }
  torch::optim::Adam opt(net->parameters());
  RefineFileMeta meta;
  meta.net = net->options();
  meta.layout = "test_layout";
  meta.steps = 42;
  meta.trained_on = "unit test";
  const std::string path = dir + "/r.pt";
  SaveRefineNet(path, meta, net, &opt);
  RefineFileMeta back;
  RefineUNet loaded = LoadRefineNet(path, &back);
  CHECK(back.layout == "test_layout");
  CHECK(back.steps == 42);
  CHECK(back.net.widths == std::vector<int>{8, 16});
  const torch::Tensor in = torch::rand({1, 6, 8, 8}), base = torch::rand({1, 4, 8, 8});
  CHECK(torch::allclose(net->forward(in, base), loaded->forward(in, base)));
  torch::optim::Adam opt2(loaded->parameters());
  CHECK(LoadRefineOptimizer(path, opt2));
  CHECK_FALSE(std::filesystem::exists(path + ".tmp"));

  { std::ofstream(dir + "/junk.pt") << "not a file"; }
  CHECK_THROWS_WITH(ReadRefineMeta(dir + "/junk.pt"), Catch::Contains("junk.pt"));
  CHECK_THROWS_WITH(ReadRefineMeta(dir + "/missing.pt"), Catch::Contains("does not exist"));
  std::filesystem::remove_all(dir);
}
