/// @file networks_losses_test.cc
/// @brief Shapes of G/D/ENET for several configs, spectral normalisation, and every P2I-NET loss
/// on hand-made tensors (values, gradient flow, switches).
#include <cmath>
#include <optional>

#include <catch2/catch.hpp>
#include <torch/torch.h>

#include "model/losses.h"
#include "model/networks.h"
#include "tests/model/model_test_util.h"

using namespace p2i::model;

namespace {

P2iConfig Tiny(int res, bool depth, const std::string& schedule) {
  P2iConfig c;
  c.resolution = res;
  c.depth = depth;
  c.g_schedule = schedule;
  c.g_min_width = 8;
  c.g_max_width = 32;
  c.g_widths.assign(static_cast<size_t>(std::log2(res) - 1), 8);
  c.g_fc_width = 16;
  c.d_base_width = 8;
  c.d_max_width = 16;
  c.latent_dim = 32;
  c.mapping_width = 16;
  c.enet_width = 8;
  c.enet_blocks = 1;
  c.Validate();
  return c;
}

torch::Tensor Leaf(std::vector<float> v, std::vector<int64_t> shape) {
  return torch::tensor(v).reshape(shape).set_requires_grad(true);
}

}  // namespace

TEST_CASE("G, D and ENET produce the configured shapes", "[unit]") {
  for (int res : {32, 64}) {
    for (bool depth : {true, false}) {
      for (std::string schedule : {"more", "fewer", "custom"}) {
        const auto c = Tiny(res, depth, schedule);
        Generator g(c);
        Discriminator d(c);
        Enhancer e(c);
        auto img = g->forward(torch::zeros({2, 7}));
        REQUIRE(img.sizes() == torch::IntArrayRef({2, c.Channels(), res, res}));
        CHECK(img.abs().max().item<float>() <= 1.0f);
        auto out = d->forward(img);
        CHECK(out.latent.sizes() == torch::IntArrayRef({2, 32}));
        CHECK(out.score.sizes() == torch::IntArrayRef({2}));
        CHECK(out.pose.sizes() == torch::IntArrayRef({2, 7}));
        CHECK(d->MapPose(torch::zeros({2, 7})).sizes() == torch::IntArrayRef({2, 32}));
        CHECK(e->forward(img).sizes() == img.sizes());
        CHECK(g->MacsPerView() > 0);
      }
    }
  }
}

TEST_CASE("the 'more' schedule grows from min to max width, 'fewer' is flat", "[unit]") {
  P2iConfig c;
  c.resolution = 256;
  c.g_schedule = "more";
  const auto more = c.GeneratorWidths();
  REQUIRE(more.size() == 7);
  CHECK(more.front() == 64);
  CHECK(more.back() == 1024);
  for (size_t i = 1; i < more.size(); ++i) CHECK(more[i] > more[i - 1]);
  c.g_schedule = "fewer";
  for (int w : c.GeneratorWidths()) CHECK(w == 64);
}

TEST_CASE("ENET starts as the identity and attention starts as the identity", "[unit]") {
  const auto c = Tiny(32, true, "custom");
  Enhancer e(c);
  auto x = torch::rand({1, 4, 32, 32}) * 2 - 1;
  CHECK(torch::allclose(e->forward(x), x));
  SelfAttention a(16, true);
  auto f = torch::randn({2, 16, 4, 4});
  CHECK(torch::allclose(a->forward(f), f));
  {
    torch::NoGradGuard ng;
    a->gamma.fill_(1.0);
  }
  CHECK_FALSE(torch::allclose(a->forward(f), f));
}

TEST_CASE("spectral normalisation bounds the largest singular value by 1", "[unit]") {
  torch::manual_seed(3);
  SNLinear lin(20, 30, true);
  {
    torch::NoGradGuard ng;
    lin->weight.mul_(10.0);
  }
  for (int i = 0; i < 50; ++i) lin->forward(torch::zeros({1, 20}));  // power iterations
  const auto w = lin->EffectiveWeight().detach();
  const auto s = std::get<1>(torch::svd(w));
  CHECK(s.max().item<double>() == Approx(1.0).epsilon(0.02));
  SNLinear plain(20, 30, false);
  {
    torch::NoGradGuard ng;
    plain->weight.mul_(10.0);
  }
  CHECK(std::get<1>(torch::svd(plain->EffectiveWeight().detach())).max().item<double>() > 2.0);
}

TEST_CASE("D_pro adds k1 * cosine only with HD", "[unit]") {
  DOutput d;
  d.latent = torch::tensor({1.0f, 0.0f, 0.0f, 1.0f}).reshape({2, 2});
  d.score = torch::tensor({0.5f, -0.5f});
  const auto mp = torch::tensor({1.0f, 0.0f, 1.0f, 0.0f}).reshape({2, 2});  // cos = 1, 0
  LossWeights w;
  w.k1 = 2.0;
  auto s = ProjectionScore(d, mp, w);
  CHECK(s[0].item<float>() == Approx(2.5));
  CHECK(s[1].item<float>() == Approx(-0.5));
  w.hd = false;
  s = ProjectionScore(d, mp, w);
  CHECK(s[0].item<float>() == Approx(0.5));
}

TEST_CASE("L_D: hinge, L_PE terms with a detached gamma, LD switch", "[unit]") {
  // One sample. real: score 0.2, pose (3,4,0...) -> ||M_l(F_l(I_r))|| = 5
  DOutput real, fake;
  real.latent = Leaf({1, 0}, {1, 2});
  real.score = Leaf({0.2f}, {1});
  real.pose = Leaf({3, 4, 0, 0, 0, 0, 0}, {1, 7});
  fake.latent = Leaf({0, 1}, {1, 2});
  fake.score = Leaf({0.1f}, {1});
  fake.pose = Leaf({3, 4, 2, 0, 0, 0, 0}, {1, 7});  // ||fake - real|| = 2
  const auto mp = Leaf({1, 0}, {1, 2});             // cos(real) = 1, cos(fake) = 0
  const auto y = torch::tensor({3.f, 4.f, 0.f, 0.f, 0.f, 0.f, 1.f}).reshape({1, 7});  // L_PE-Ir = 1
  LossWeights w;
  w.k1 = 1.0;
  w.k2 = 0.5;
  auto t = DiscriminatorLoss(real, fake, mp, y, w);
  // D_pro real = 0.2 + 1 = 1.2 -> relu(1 - 1.2) = 0; fake = 0.1 -> relu(1.1) = 1.1
  CHECK(t.pro.item<float>() == Approx(1.1));
  CHECK(t.pe_real.item<float>() == Approx(1.0));
  // gamma = |0.2 - 0.1| * 5 = 0.5 ; L_PE-Ig = max(2 - 0.5, 0) = 1.5
  CHECK(t.gamma.item<float>() == Approx(0.5));
  CHECK(t.pe_fake.item<float>() == Approx(1.5));
  CHECK(t.total.item<float>() == Approx(1.1 + 0.5 * (1.0 + 1.5)));
  CHECK_FALSE(t.gamma.requires_grad());
  t.total.backward();
  // Scores get gradient only through the hinge: d/d fake.score = +1 (through hinge), and
  // NOT through gamma (which would add -k2 * 5 * sign). real.score is in the flat hinge part.
  CHECK(fake.score.grad().item<float>() == Approx(1.0));
  CHECK(real.score.grad().item<float>() == Approx(0.0));
  REQUIRE(fake.pose.grad().defined());
  CHECK(fake.pose.grad().abs().sum().item<float>() > 0);
  // LD off: the PE terms vanish from the total.
  w.ld = false;
  auto t2 = DiscriminatorLoss(real, fake, mp, y, w);
  CHECK(t2.total.item<float>() == Approx(1.1));
  // HD off: the cosine leaves D_pro: real 0.2 -> relu(0.8) = 0.8
  w.hd = false;
  auto t3 = DiscriminatorLoss(real, fake, mp, y, w);
  CHECK(t3.pro.item<float>() == Approx(0.8 + 1.1));
}

TEST_CASE("L_PE-Ig is zero inside the gamma tolerance", "[unit]") {
  DOutput real, fake;
  real.latent = Leaf({1, 0}, {1, 2});
  real.score = Leaf({1.0f}, {1});
  real.pose = Leaf({3, 4, 0, 0, 0, 0, 0}, {1, 7});
  fake.latent = Leaf({0, 1}, {1, 2});
  fake.score = Leaf({0.0f}, {1});                    // gamma = 1 * 5 = 5
  fake.pose = Leaf({3, 4, 2, 0, 0, 0, 0}, {1, 7});  // distance 2 < 5
  auto t = DiscriminatorLoss(real, fake, Leaf({1, 0}, {1, 2}), torch::zeros({1, 7}), LossWeights{});
  CHECK(t.pe_fake.item<float>() == Approx(0.0));
}

TEST_CASE("L_G = -D_pro(I_g) + pose error, the pose term only with LD", "[unit]") {
  DOutput fake;
  fake.latent = Leaf({1, 0}, {1, 2});
  fake.score = Leaf({0.3f}, {1});
  fake.pose = Leaf({0, 0, 0, 0, 0, 0, 0}, {1, 7});
  const auto mp = torch::tensor({0.f, 1.f}).reshape({1, 2});  // cos 0
  const auto y = torch::tensor({0.f, 0.f, 2.f, 0.f, 0.f, 0.f, 0.f}).reshape({1, 7});
  LossWeights w;
  auto t = GeneratorLoss(fake, mp, y, w);
  CHECK(t.total.item<float>() == Approx(-0.3 + 2.0));
  t.total.backward();
  CHECK(fake.score.grad().item<float>() == Approx(-1.0));
  CHECK(fake.pose.grad()[0][2].item<float>() == Approx(-1.0));
  w.ld = false;
  CHECK(GeneratorLoss(fake, mp, y, w).total.item<float>() == Approx(-0.3));
}

TEST_CASE("Roberts cross and the ENET loss", "[unit]") {
  // 1 x 1 x 2 x 2 image [[1, 2], [3, 5]] -> a - d = 1 - 5 = -4, b - c = 2 - 3 = -1
  auto img = torch::tensor({1.f, 2.f, 3.f, 5.f}).reshape({1, 1, 2, 2});
  auto r = Roberts(img);
  REQUIRE(r.sizes() == torch::IntArrayRef({1, 2, 1, 1}));
  CHECK(r[0][0][0][0].item<float>() == Approx(-4));
  CHECK(r[0][1][0][0].item<float>() == Approx(-1));
  auto real = torch::zeros({1, 1, 2, 2});
  auto e = img.clone().set_requires_grad(true);
  LossWeights w;
  w.k3 = 2.0;
  auto t = EnetLoss(e, real, w);
  const double pixel = std::sqrt(1 + 4 + 9 + 25.0), edge = std::sqrt(16 + 1.0);
  CHECK(t.pixel.item<float>() == Approx(pixel));
  CHECK(t.edge.item<float>() == Approx(edge));
  CHECK(t.total.item<float>() == Approx(pixel + 2 * edge));
  t.total.backward();
  CHECK(e.grad().abs().sum().item<float>() > 0);
}

TEST_CASE("phase 2: ENET trains while the frozen G gets no gradient", "[unit]") {
  const auto c = Tiny(32, true, "custom");
  Generator g(c);
  Enhancer e(c);
  for (auto& p : g->parameters()) p.set_requires_grad(false);
  torch::Tensor gen;
  {
    torch::NoGradGuard ng;
    gen = g->forward(torch::zeros({2, 7}));
  }
  auto t = EnetLoss(e->forward(gen), torch::zeros_like(gen), LossWeights{});
  t.total.backward();
  for (const auto& p : g->parameters()) CHECK_FALSE(p.grad().defined());
  double enet_grad = 0;
  for (const auto& p : e->parameters())
    if (p.grad().defined()) enet_grad += p.grad().abs().sum().item<double>();
  CHECK(enet_grad > 0);
}

TEST_CASE("Fourier pose encoding: 7 (1 + 2 B) inputs, sin/cos of 2^k pi y, G takes it", "[unit]") {
  const auto y = torch::tensor({{0.25f, -0.5f, 0.f, 0.f, 0.f, 0.f, 1.f}});
  const auto e = EncodePose(y, 2);
  REQUIRE(e.sizes() == torch::IntArrayRef({1, 35}));
  CHECK(torch::equal(e.slice(1, 0, 7), y));
  CHECK(e[0][7].item<float>() == Approx(std::sin(M_PI * 0.25)));       // sin(pi y0)
  CHECK(e[0][14].item<float>() == Approx(std::cos(M_PI * 0.25)));      // cos(pi y0)
  CHECK(e[0][22].item<float>() == Approx(std::sin(2 * M_PI * -0.5)).margin(1e-6));  // sin(2 pi y1)
  CHECK(torch::equal(EncodePose(y, 0), y));
  auto c = Tiny(32, true, "custom");
  c.pose_encoding = "fourier";
  c.fourier_bands = 3;
  c.Validate();
  CHECK(c.PoseInputs() == 49);
  Generator g(c);
  CHECK(g->fc1->weight.size(1) == 49);
  CHECK(g->forward(torch::zeros({2, 7})).sizes() == torch::IntArrayRef({2, 4, 32, 32}));
}

TEST_CASE("reconstruction L1 and the R1 penalty values", "[unit]") {
  const auto a = torch::tensor({{1.f, -1.f}, {0.5f, 0.f}});
  const auto b = torch::zeros({2, 2});
  CHECK(ReconstructionLoss(a, b).item<double>() == Approx(2.5 / 4));
  // score = sum(w * x) per sample: its gradient w.r.t. x is w, so R1 = gamma / 2 * ||w||^2.
  auto x = torch::randn({3, 1, 2, 2}).requires_grad_(true);
  const auto w = torch::tensor({1.f, 2.f, -2.f, 0.f}).reshape({1, 1, 2, 2});
  const auto score = (x * w).sum({1, 2, 3});
  const auto r1 = R1Penalty(score, x, 10.0);
  CHECK(r1.item<double>() == Approx(5.0 * 9.0));
  CHECK(r1.requires_grad() == false);  // w is a constant here: no parameter to train
}

TEST_CASE("G step with D frozen (FrozenScope): the same G gradients, no D weight gradients",
          "[unit]") {
  const auto c = Tiny(32, true, "custom");
  torch::manual_seed(3);
  Generator g(c);
  Discriminator d(c);
  const LossWeights w = LossWeights::From(c);
  const auto y = torch::rand({2, 7}) * 2 - 1;
  // The SN power iteration updates D's u vectors in every forward: both passes start from the
  // same buffers so they see the same D.
  std::vector<torch::Tensor> buffers;
  for (const auto& b : d->buffers()) buffers.push_back(b.clone());
  auto restore_buffers = [&] {
    torch::NoGradGuard ng;
    size_t i = 0;
    for (auto& b : d->buffers()) b.copy_(buffers[i++]);
  };
  auto run = [&](bool freeze) {
    restore_buffers();
    g->zero_grad();
    d->zero_grad();
    std::optional<FrozenScope> frozen;
    if (freeze) frozen.emplace(*d);
    auto gl = GeneratorLoss(d->forward(g->forward(y)), d->MapPose(y), y, w);
    gl.total.backward();
    std::vector<torch::Tensor> out;
    for (const auto& p : g->parameters()) out.push_back(p.grad().clone());
    bool d_grad = false;
    for (const auto& p : d->parameters())
      d_grad |= p.grad().defined() && p.grad().abs().sum().item<double>() > 0;
    CHECK(d_grad == !freeze);
    return out;
  };
  const auto plain = run(false);
  const auto frozen = run(true);
  REQUIRE(plain.size() == frozen.size());
  for (size_t i = 0; i < plain.size(); ++i) CHECK(torch::allclose(plain[i], frozen[i], 1e-5, 1e-6));
  for (const auto& p : d->parameters()) CHECK(p.requires_grad());  // restored
}

namespace {

// A pose at the origin rotated by `deg` degrees about z, as scene::Pose stores it (qw >= 0).
std::array<double, 7> YawPose(double deg) {
  const double h = 0.5 * deg * M_PI / 180.0;
  double qz = std::sin(h), qw = std::cos(h);
  if (qw < 0) qz = -qz, qw = -qw;
  return {0, 0, 0, 0, 0, qz, qw};
}

double Distance(const std::array<float, 7>& a, const std::array<float, 7>& b) {
  double s = 0;
  for (int i = 0; i < 7; ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(s);
}

}  // namespace

TEST_CASE("the pose normaliser keeps rotations near 180 deg continuous", "[unit]") {
  // A capture looking back along the world frame: yaw 170-190 deg, where the canonical qw >= 0
  // sign flips the quaternion (the study-room data's case).
  std::vector<std::array<double, 7>> poses;
  for (double deg = 170; deg <= 190.001; deg += 2) poses.push_back(YawPose(deg));
  const auto n = PoseNormalizer::FromPoses(poses);
  // The principal rotation is the middle one, 180 deg about z (up to sign).
  CHECK(std::abs(n.q_ref[2]) == Approx(1.0).margin(1e-6));
  CHECK(n.q_ref[3] >= 0);
  // Two rotations 2 deg apart on either side of 180 deg are 2 deg apart in the input too
  // (|dq| = 2 sin(0.5 deg) ~ 0.017); with the plain sign they were ~2 apart.
  const auto a = n.Normalize(YawPose(179)), b = n.Normalize(YawPose(181));
  CHECK(Distance(a, b) < 0.03);
  PoseNormalizer plain = n;
  plain.q_ref = {0, 0, 0, 1};
  CHECK(Distance(plain.Normalize(YawPose(179)), plain.Normalize(YawPose(181))) > 1.9);
  // Every training rotation lands on one side.
  for (const auto& p : poses) CHECK(n.Normalize(p)[5] * a[5] > 0);
}

TEST_CASE("the pose normaliser leaves captures away from 180 deg as the qw >= 0 sign has them",
          "[unit]") {
  // Rotations within 90 deg of identity: every input equals the plain normaliser's, so models
  // trained before q_ref existed (identity q_ref) see the same inputs.
  std::vector<std::array<double, 7>> poses;
  for (double deg = -80; deg <= 60.001; deg += 10) {
    auto p = YawPose(deg);
    p[0] = deg / 100.0;
    poses.push_back(p);
  }
  const auto n = PoseNormalizer::FromPoses(poses);
  PoseNormalizer plain = n;
  plain.q_ref = {0, 0, 0, 1};
  for (const auto& p : poses) CHECK(Distance(n.Normalize(p), plain.Normalize(p)) == 0.0);
  CHECK(PoseNormalizer::PrincipalRotation({}) == std::array<double, 4>{0, 0, 0, 1});
}
