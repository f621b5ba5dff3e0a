/// @file trainer_test.cc
/// @brief Checkpoints (round trip, version refusal, atomic write), exact resume, the divergence
/// guard, the synthesizer, and a short end-to-end training run on procedural frames.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include "model/checkpoint.h"
#include "model/densify.h"
#include "model/p2i_synthesizer.h"
#include "model/pose_dependence.h"
#include "model/procedural_dataset.h"
#include "model/trainer.h"
#include "tests/model/model_test_util.h"
#include "tests/read_file.h"

namespace fs = std::filesystem;
using namespace p2i::model;
using namespace p2i::model::testing;

using p2i::testing::ReadFile;

TEST_CASE("checkpoint round trip keeps weights and metadata", "[unit]") {
  const auto dir = TempDir("roundtrip");
  const auto c = TinyConfig();
  torch::manual_seed(1);
  Networks a(c);
  CheckpointMeta meta;
  meta.config = c;
  meta.normalizer.t_min = {-1.5, 0.25, 2};
  meta.normalizer.t_max = {3, 4, 5};
  meta.normalizer.q_ref = {0.5, -0.5, 0.5, 0.5};
  meta.phase1_step = 17;
  meta.phase2_step = 4;
  meta.lr_scale = 0.25;
  meta.camera = p2i::scene::CameraInfo::Pinhole(32, 32, 20, 21, 15.5, 15.5);
  SaveCheckpoint(dir + "/c.pt", meta, a, {});
  torch::manual_seed(2);
  Networks b(c);
  CHECK_FALSE(SameParameters(*a.g, *b.g));
  const auto loaded = LoadCheckpoint(dir + "/c.pt", b, {}, false);
  CHECK(SameParameters(*a.g, *b.g));
  CHECK(SameParameters(*a.d, *b.d));
  CHECK(SameParameters(*a.e, *b.e));
  CHECK(loaded.phase1_step == 17);
  CHECK(loaded.phase2_step == 4);
  CHECK(loaded.lr_scale == 0.25);
  CHECK(loaded.normalizer.t_min[0] == -1.5);
  CHECK(loaded.normalizer.t_max[2] == 5);
  CHECK(loaded.normalizer.q_ref == std::array<double, 4>{0.5, -0.5, 0.5, 0.5});
  CHECK(loaded.camera.fy() == 21);
  CHECK(loaded.config.ToYamlString() == c.ToYamlString());
  fs::remove_all(dir);
}

TEST_CASE("a checkpoint without a reference rotation loads with the qw >= 0 sign it was trained on",
          "[unit]") {
  CheckpointMeta meta;
  meta.config = TinyConfig();
  meta.normalizer.q_ref = {0, 0, 1, 0};
  std::string text = meta.ToJson();
  CHECK(CheckpointMeta::FromJson(text, "new.pt").normalizer.q_ref ==
        std::array<double, 4>{0, 0, 1, 0});
  auto j = nlohmann::json::parse(text);
  REQUIRE(j.erase("pose_q_ref") == 1);
  text = j.dump();
  CHECK(CheckpointMeta::FromJson(text, "old.pt").normalizer.q_ref ==
        std::array<double, 4>{0, 0, 0, 1});
}

TEST_CASE("a checkpoint of another format version is refused with a clear message", "[unit]") {
  const auto dir = TempDir("version");
  const auto c = TinyConfig();
  Networks a(c);
  CheckpointMeta meta;
  meta.config = c;
  meta.format_version = kCheckpointFormatVersion + 1;
  SaveCheckpoint(dir + "/c.pt", meta, a, {});
  CHECK_THROWS_WITH(ReadCheckpointMeta(dir + "/c.pt"),
                    Catch::Contains("format version " + std::to_string(kCheckpointFormatVersion + 1)) &&
                        Catch::Contains("this build reads version"));
  CHECK_THROWS_WITH(LoadSynthesizer(dir + "/c.pt"), Catch::Contains("format version"));
  CHECK_THROWS_WITH(ReadCheckpointMeta(dir + "/missing.pt"), Catch::Contains("does not exist"));
  fs::remove_all(dir);
}

TEST_CASE("atomic write: a failed write leaves the old file and no temporary", "[unit]") {
  const auto dir = TempDir("atomic");
  const std::string path = dir + "/file.bin";
  WriteFileAtomically(path, [](const std::string& tmp) { std::ofstream(tmp) << "old"; });
  CHECK(ReadFile(path) == "old");
  CHECK_THROWS_WITH(WriteFileAtomically(path,
                                        [](const std::string& tmp) {
                                          std::ofstream(tmp) << "half-writ";
                                          throw std::runtime_error("disk full");
                                        }),
                    Catch::Contains("disk full"));
  CHECK(ReadFile(path) == "old");
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    (void)e;
    ++files;
  }
  CHECK(files == 1);
  // A real checkpoint write leaves only the checkpoint.
  const auto c = TinyConfig();
  Networks n(c);
  CheckpointMeta meta;
  meta.config = c;
  SaveCheckpoint(dir + "/c.pt", meta, n, {});
  files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.path().string().find(".tmp") == std::string::npos ? 1 : 100;
  CHECK(files == 2);
  fs::remove_all(dir);
}

TEST_CASE("resume after K steps equals an unbroken run of 2K steps", "[unit]") {
  const auto data = MakeProceduralDataset(12, 32);
  REQUIRE(data.frames.size() == 12);
  const auto c = TinyConfig();
  const auto dir_a = TempDir("resume_a"), dir_b = TempDir("resume_b");
  Trainer(c, Quiet(dir_a, 8)).Run(data, data);
  Trainer(c, Quiet(dir_b, 4)).Run(data, data);
  auto resume = Quiet(dir_b, 8);
  resume.resume = true;
  const auto report = Trainer(c, resume).Run(data, data);
  CHECK(report.phase1_steps == 8);
  Networks a(c), b(c);
  const auto ma = LoadCheckpoint(Trainer::CheckpointPath(dir_a), a, {}, false);
  const auto mb = LoadCheckpoint(Trainer::CheckpointPath(dir_b), b, {}, false);
  CHECK(ma.phase1_step == 8);
  CHECK(mb.phase1_step == 8);
  CHECK(SameParameters(*a.g, *b.g));
  CHECK(SameParameters(*a.d, *b.d));
  // And training really changed the weights (the test is not comparing two untouched nets).
  torch::manual_seed(c.seed);
  Networks fresh(c);
  CHECK_FALSE(SameParameters(*a.g, *fresh.g));
  fs::remove_all(dir_a);
  fs::remove_all(dir_b);
}

TEST_CASE("lr_decay_steps lowers phase 1's learning rates linearly over the last steps", "[unit]") {
  const auto data = MakeProceduralDataset(12, 32);
  auto c = TinyConfig();
  c.lr_decay_steps = 10;
  const auto dir_a = TempDir("decay_a"), dir_b = TempDir("decay_b"), dir_c = TempDir("decay_c");
  const auto report = Trainer(c, Quiet(dir_a, 20)).Run(data, data);
  const auto log = ReadFile(report.log_path);
  // Logged every 10 steps: step 10 is before the decay (factor 1), step 20 is its last (1/10).
  CHECK(log.find("\"lr_decay\":1.0,") != std::string::npos);
  CHECK(log.find("\"lr_decay\":0.1,") != std::string::npos);
  auto constant = c;
  constant.lr_decay_steps = 0;
  const auto plain = Trainer(constant, Quiet(dir_b, 20)).Run(data, data);
  CHECK(ReadFile(plain.log_path).find("lr_decay") == std::string::npos);
  Networks a(c), b(c);
  LoadCheckpoint(Trainer::CheckpointPath(dir_a), a, {}, false);
  LoadCheckpoint(Trainer::CheckpointPath(dir_b), b, {}, false);
  CHECK_FALSE(SameParameters(*a.g, *b.g));  // the decay reached the optimiser
  // A schedule key: a resumed run takes the given config's value, not the checkpoint's.
  Trainer(constant, Quiet(dir_c, 10)).Run(data, data);
  const auto resumed = Trainer(c, Quiet(dir_c, 20, 1, /*resume=*/true)).Run(data, data);
  CHECK(ReadFile(resumed.log_path).find("\"lr_decay\":0.1,") != std::string::npos);
  c.lr_decay_steps = -1;
  CHECK_THROWS_WITH(c.Validate(), Catch::Contains("lr_decay_steps"));
  fs::remove_all(dir_a);
  fs::remove_all(dir_b);
  fs::remove_all(dir_c);
}

TEST_CASE("the divergence guard rolls back on an injected NaN and lowers the LR", "[unit]") {
  const auto data = MakeProceduralDataset(12, 32);
  const auto c = TinyConfig();
  const auto dir = TempDir("nan");
  auto opt = Quiet(dir, 10);
  opt.inject_nan_at_step = 5;
  const auto report = Trainer(c, opt).Run(data, data);
  CHECK(report.rollbacks == 1);
  CHECK(report.phase1_steps == 10);
  const auto log = ReadFile(report.log_path);
  CHECK(log.find("\"event\":\"rollback\"") != std::string::npos);
  CHECK(log.find("\"to_phase1_step\":3") != std::string::npos);  // last checkpoint before 5
  Networks n(c);
  const auto meta = LoadCheckpoint(report.checkpoint_path, n, {}, false);
  CHECK(meta.lr_scale == 0.5);
  for (const auto& p : n.g->parameters()) REQUIRE(torch::isfinite(p).all().item<bool>());
  for (const auto& p : n.d->parameters()) REQUIRE(torch::isfinite(p).all().item<bool>());
  fs::remove_all(dir);
}

TEST_CASE("validation logs the pose-dependence score, and recon_weight, fourier and r1 train", "[unit]") {
  const auto dir = TempDir("posedep");
  const auto data = MakeProceduralDataset(12, 32);
  p2i::scene::RgbdDataset train = data, val = data;
  train.frames.resize(8);
  val.frames.erase(val.frames.begin(), val.frames.begin() + 8);
  auto c = TinyConfig();
  c.recon_weight = 10.0;
  c.pose_encoding = "fourier";
  c.fourier_bands = 2;
  c.r1_gamma = 1.0;
  c.Validate();
  const auto report = Trainer(c, Quiet(dir, 5)).Run(train, val);
  CHECK(std::isfinite(report.val_pose_dependence));
  CHECK(report.val_pose_dependence >= 0.0);
  const std::string log = ReadFile(report.log_path);
  CHECK(log.find("\"pose_dependence\":") != std::string::npos);
  CHECK(log.find("\"g_recon\":") != std::string::npos);
  CHECK(log.find("\"d_r1\":") != std::string::npos);
  // An untrained tiny G renders nearly one image: the warning event is logged.
  if (report.val_pose_dependence < kPoseDependenceWarn)
    CHECK(log.find("\"event\":\"warning\"") != std::string::npos);
  fs::remove_all(dir);
}

// The mean grey level the CNN baseline renders over `data`'s poses after `steps` steps with
// densify_real_share `share` and densify_steps `densify_steps`.
double MeanGreyAfterTraining(const p2i::scene::RgbdDataset& data, double share, int steps,
                             const std::string& dir, int densify_steps = -1) {
  auto c = TinyConfig("cnn_baseline");
  c.densify_real_share = share;
  c.densify_steps = densify_steps;
  c.lr_g = 1e-2;  // a few steps reach the L2 optimum, the batches' mean image
  c.Validate();
  const auto report = Trainer(c, Quiet(dir, steps)).Run(data, data);
  SynthesizerOptions o;
  o.threads = 1;
  auto synth = LoadSynthesizer(report.checkpoint_path, o);
  double sum = 0;
  for (const auto& f : data.frames) sum += cv::mean(synth->Render(f.pose).rgb)[0];
  return sum / static_cast<double>(data.frames.size());
}

// 16 frames: 4 captured ones all white, 12 densified ones (model/densify.h ids) all black.
p2i::scene::RgbdDataset WhiteCapturedBlackDensified() {
  auto data = MakeProceduralDataset(16, 32);
  for (size_t i = 0; i < data.frames.size(); ++i) {
    auto& f = data.frames[i];
    f.rgb.setTo(cv::Scalar::all(i % 4 == 0 ? 255 : 0));
    if (i % 4 != 0) f.id = std::string(kDensifiedIdPrefix) + std::to_string(i);
  }
  return data;
}

TEST_CASE("densify_real_share sets the captured frames' share of what the model learns", "[unit]") {
  // 4 captured white frames and 12 densified black ones: drawn uniformly (share off) a quarter
  // of each batch is white; with share 0.9 nine tenths are. The CNN's L2 optimum follows.
  const auto data = WhiteCapturedBlackDensified();
  const auto dir_off = TempDir("share_off"), dir_on = TempDir("share_on");
  const double off = MeanGreyAfterTraining(data, 0.0, 60, dir_off);
  const double on = MeanGreyAfterTraining(data, 0.9, 60, dir_on);
  INFO("mean grey: share off " << off << ", share 0.9 " << on);
  CHECK(off < 128);
  CHECK(on > 160);
  const std::string log = ReadFile(dir_on + "/train_log.jsonl");
  CHECK(log.find("\"densified_frames\":12") != std::string::npos);
  CHECK(log.find("\"densify_real_share\":0.9") != std::string::npos);
  fs::remove_all(dir_off);
  fs::remove_all(dir_on);
}

TEST_CASE("densify_steps ends the densified views' part in the batches at that step", "[unit]") {
  // As above: 4 captured white frames, 12 densified black ones. Densified views in every step,
  // the L2 optimum is a quarter white; with densify_steps 30 of 60 the last 30 steps see the
  // white captured frames only and the CNN ends near white.
  const auto data = WhiteCapturedBlackDensified();
  const auto dir_all = TempDir("dsteps_all"), dir_30 = TempDir("dsteps_30");
  const double all = MeanGreyAfterTraining(data, 0.0, 60, dir_all, -1);
  const double until30 = MeanGreyAfterTraining(data, 0.0, 60, dir_30, 30);
  INFO("mean grey: densified throughout " << all << ", until step 30 " << until30);
  CHECK(all < 128);
  CHECK(until30 > 200);
  CHECK(ReadFile(dir_30 + "/train_log.jsonl").find("\"densify_steps\":30") != std::string::npos);
  fs::remove_all(dir_all);
  fs::remove_all(dir_30);
}

TEST_CASE("the synthesizer renders RGB-D in metres with invalid depth 0", "[unit]") {
  const auto dir = TempDir("synth");
  const auto c = TinyConfig();
  Networks n(c);
  CheckpointMeta meta;
  meta.config = c;
  meta.camera.image_width = 32;
  meta.camera.image_height = 32;
  {
    torch::NoGradGuard ng;
    n.g->to_image->bias[3].fill_(20.0);  // depth channel saturates at +1 = depth_max
  }
  SaveCheckpoint(dir + "/far.pt", meta, n, {});
  {
    torch::NoGradGuard ng;
    n.g->to_image->bias[3].fill_(-20.0);  // -1 = 0 m = invalid
  }
  SaveCheckpoint(dir + "/near.pt", meta, n, {});
  SynthesizerOptions o;
  o.threads = 1;
  auto far = LoadSynthesizer(dir + "/far.pt", o);
  auto near = LoadSynthesizer(dir + "/near.pt", o);
  const p2i::scene::Pose pose;
  const auto v = far->Render(pose);
  REQUIRE(v.rgb.type() == CV_8UC3);
  REQUIRE(v.depth.type() == CV_32FC1);
  CHECK(v.rgb.cols == 32);
  CHECK(v.depth.rows == 32);
  double lo, hi;
  cv::minMaxLoc(v.depth, &lo, &hi);
  CHECK(lo == Approx(c.depth_max).epsilon(1e-3));
  cv::minMaxLoc(near->Render(pose).depth, &lo, &hi);
  CHECK(hi == 0.0);
  // Batch == single renders; parameters and FLOPs are reported (G only: ENET untrained).
  const std::vector<p2i::scene::Pose> poses = {
      pose, p2i::scene::Pose(Eigen::Vector3d(0.5, 0, 0), Eigen::Quaterniond::Identity())};
  const auto batch = far->RenderBatch(poses);
  REQUIRE(batch.size() == 2);
  CHECK(cv::norm(batch[1].rgb, far->Render(poses[1]).rgb, cv::NORM_INF) <= 1.0);
  CHECK(far->Name() == "p2i_net_g");
  CHECK(far->ParameterCount() == CountParameters(*n.g));
  CHECK(far->FlopsPerView() == Approx(2.0 * n.g->MacsPerView()));
  SynthesizerOptions want_enet = o;
  want_enet.stage = "g+enet";
  CHECK_THROWS_WITH(LoadSynthesizer(dir + "/far.pt", want_enet), Catch::Contains("no trained ENET"));
  fs::remove_all(dir);
}

// A G that carries no pose information leaves ENET to learn the mean image at best (the
// floor below); 1 dB above it needs pose-dependent images.
constexpr double kMarginDb = 1.0;
// Phase 1 alone (G+D, the adversarial path; G's moving average renders): measured +1.1 to +1.5 dB
// above the mean image at 500-1000 steps with this config (docs/MODEL.md, phase-1 study); the
// assertion keeps 0.5 dB of it so that another machine's float rounding (a different GAN
// trajectory) does not fail it. Without g_ema or with the 8/16/32-wide D the same run stays
// 0.5-1.5 dB BELOW the mean image.
constexpr double kPhase1MarginDb = 0.5;

TEST_CASE("end to end: P2I-NET beats the mean image on held-out procedural frames", "[slow]") {
  // 96 frames along a loop in the analytic room, every 8th held out (interpolation between
  // training poses, the paper's setting (a)). One thread: on a loaded 2-core box LibTorch's
  // second OpenMP thread mostly spins.
  auto all = MakeProceduralDataset(96, 64);
  p2i::scene::RgbdDataset train, val;
  train.camera = val.camera = all.camera;
  for (size_t i = 0; i < all.frames.size(); ++i)
    (i % 8 == 4 ? val : train).frames.push_back(all.frames[i]);
  P2iConfig c;
  c.name = "e2e";
  c.resolution = 32;
  c.g_schedule = "custom";
  c.g_widths = {32, 32, 16, 8};
  c.g_fc_width = 64;
  c.d_base_width = 16;
  c.d_max_width = 64;
  c.latent_dim = 128;
  c.mapping_width = 64;
  c.g_ema = 0.99;
  c.enet_width = 16;
  c.enet_blocks = 1;
  c.batch_size = 8;
  c.lr_g = c.lr_d = 1e-3;
  c.val_every = 100;
  c.checkpoint_every = 100;
  c.steps_phase1 = 800;
  c.steps_phase2 = 300;
  c.Validate();
  const auto dir = TempDir("e2e");
  TrainerOptions o;
  o.out_dir = dir;
  o.threads = 1;
  o.progress = false;
  o.max_val_frames = 12;
  o.phase = 1;
  const auto phase1 = Trainer(c, o).Run(train, val);
  INFO("phase 1 alone: val PSNR " << phase1.val_psnr << " dB, mean image "
                                  << phase1.mean_image_val_psnr << " dB");
  CHECK(phase1.phase1_steps == 800);
  CHECK(phase1.val_psnr > phase1.mean_image_val_psnr + kPhase1MarginDb);
  INFO("phase 1 pose-dependence " << phase1.val_pose_dependence);
  CHECK(phase1.val_pose_dependence > kPoseDependenceWarn);
  o.phase = 2;
  const auto report = Trainer(c, o).Run(train, val);
  INFO("with ENET: val PSNR " << report.val_psnr << " dB, mean image " << report.mean_image_val_psnr
                              << " dB");
  CHECK(report.phase2_steps == 300);
  CHECK(report.val_psnr > report.mean_image_val_psnr + kMarginDb);
  auto synth = LoadSynthesizer(report.checkpoint_path);
  CHECK(synth->Name() == "p2i_net");
  fs::remove_all(dir);
}

P2iConfig AutoBandsConfig() { return AutoFourierBandsConfig(TinyConfig()); }

int CheckpointBands(const std::string& path) {
  return ReadCheckpointMeta(path).config.fourier_bands;
}

TEST_CASE("fourier_bands: auto takes the count from the captured frames' spacing and saves it",
          "[unit]") {
  // Per-axis normalisation: n frames along x lie 2 / ((n - 1) 1.1) apart in the input
  // (margin 5 % per side), so 8 frames: 0.26 -> 2 bands; 32 frames: 0.059 -> 4 bands.
  const auto sparse = FramesOnALine(8, 0), dense = FramesOnALine(32, 0);
  // 8 captured frames with 3 densified views in every gap: counted, the views would make the
  // spacing a quarter (4 bands); the capture's spacing is the captured frames'.
  const auto filled = FramesOnALine(8, 3);
  REQUIRE(filled.frames.size() == 29);
  const auto dir_s = TempDir("auto_sparse"), dir_d = TempDir("auto_dense"),
             dir_f = TempDir("auto_filled");
  const auto rs = Trainer(AutoBandsConfig(), Quiet(dir_s, 2)).Run(sparse, sparse);
  const auto rd = Trainer(AutoBandsConfig(), Quiet(dir_d, 2)).Run(dense, dense);
  const auto rf = Trainer(AutoBandsConfig(), Quiet(dir_f, 2)).Run(filled, filled);
  CHECK(CheckpointBands(rs.checkpoint_path) == 2);
  CHECK(CheckpointBands(rd.checkpoint_path) == 4);
  CHECK(CheckpointBands(rf.checkpoint_path) == 2);
  // The start event says what was chosen and from what spacing.
  const auto start = StartEvent(rs.log_path);
  CHECK(start.at("event") == "start");
  CHECK(start.at("fourier_bands") == 2);
  CHECK(start.at("pose_spacing").get<double>() == Approx(2.0 / (7 * 1.1)).epsilon(1e-4));
  // The saved model renders with the chosen count.
  SynthesizerOptions so;
  so.threads = 1;
  CHECK(LoadSynthesizer(rd.checkpoint_path, so)->Render(dense.frames[3].pose).rgb.cols == 32);
  fs::remove_all(dir_d);
  fs::remove_all(dir_f);

  // Resuming with auto keeps the checkpoint's count; so does a warm start on other data.
  const auto resumed = Trainer(AutoBandsConfig(), Quiet(dir_s, 4, 1, true)).Run(sparse, sparse);
  CHECK(resumed.phase1_steps == 4);
  CHECK(CheckpointBands(resumed.checkpoint_path) == 2);
  const auto dir_w = TempDir("auto_warm");
  auto o = Quiet(dir_w, 2);
  o.init_from = rs.checkpoint_path;
  const auto warm = Trainer(AutoBandsConfig(), o).Run(dense, dense);
  CHECK(CheckpointBands(warm.checkpoint_path) == 2);
  fs::remove_all(dir_s);
  fs::remove_all(dir_w);
}
