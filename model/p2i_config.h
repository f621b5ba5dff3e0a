/// @file p2i_config.h
/// @brief Configuration of a P2I-NET (or CNN-baseline) model and its training: network sizes,
/// loss switches and weights, optimiser settings. Torch-free; read from the preset YAML files in
/// model/presets/.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace p2i::model {

/// Everything that defines a model and how it is trained. A value type (thread-compatible).
/// Unknown YAML keys are errors. See docs/MODEL.md for how each field reads the paper.
/// `fourier_bands: auto` in YAML (P2iConfig::fourier_bands).
constexpr int kAutoFourierBands = 0;

struct P2iConfig {
  std::string name = "p2i_net";
  /// "p2i_net" (adversarial, phases 1 and 2) or "cnn_baseline" (the same G trained by plain L2
  /// regression to the image in phase 1; it has no D and no ENET).
  std::string model = "p2i_net";

  // --- sizes ---
  int resolution = 64;     ///< square output side, a power of two in [32, 512]
  bool depth = true;       ///< RGB-D (4 channels) when true, RGB (3) when false
  /// "more": G widths grow geometrically from g_min_width (4x4 seed) to g_max_width (output
  /// resolution), the paper's schedule; "fewer": g_min_width everywhere; "custom": g_widths.
  std::string g_schedule = "custom";
  int g_min_width = 64;
  int g_max_width = 1024;
  /// custom only: one width per G stage, stage 0 at 4x4 and the last at `resolution`, so
  /// log2(resolution) - 1 entries.
  std::vector<int> g_widths = {256, 256, 128, 64, 32};
  int g_fc_width = 256;          ///< hidden width of the pose MLP before the 4x4 seed
  /// Feature normalisation in G after every conv (and the 4x4 seed): "none" or "pixel" (each
  /// pixel's feature vector scaled to unit RMS, ProGAN's PixelNorm: per sample, no batch
  /// statistics, so batch-1 inference equals training).
  std::string g_norm = "none";
  /// Encoding of the normalised pose before G's MLP (not in the paper; docs/MODEL.md "learn_128"):
  /// "none" = the 7-vector as is; "fourier" = [y, sin(2^k pi y), cos(2^k pi y)] for
  /// k = 0 .. fourier_bands - 1 (Tancik et al. 2020), 7 (1 + 2 fourier_bands) inputs.
  std::string pose_encoding = "none";
  /// 1 .. 16, or kAutoFourierBands ("auto" in YAML): training chooses the count from how far
  /// apart the captured training poses lie in the normalised input (model/pose_spacing.h) and
  /// saves the chosen count in the checkpoint's config; resuming or warm-starting adopts the
  /// checkpoint's count. A network cannot be built while it is still "auto".
  int fourier_bands = 6;
  int d_base_width = 32;         ///< D's first block width, doubling per block up to d_max_width
  int d_max_width = 512;
  int latent_dim = 1024;         ///< F_l size (the paper's 1024)
  int mapping_width = 256;       ///< hidden width of M_p and M_l
  bool attention = true;         ///< a self-attention block after each D conv block
  int attention_max_res = 32;    ///< attention only on D feature maps up to this side (cost)
  bool spectral_norm = true;     ///< on every conv/linear of D and M_d (and M_p, M_l: sn_mappings)
  bool sn_mappings = true;       ///< spectral norm also on M_p and M_l (when spectral_norm)
  bool enet = true;              ///< train (phase 2) and use ENET
  int enet_width = 32;
  int enet_blocks = 3;           ///< residual blocks

  // --- losses ---
  bool hd = true;   ///< pose consistency in latent space: the cosine term of D_pro
  bool ld = true;   ///< pose consistency in world space: L_PE terms and G's pose term
  double k1 = 1.0;
  double k2 = 1.0;
  double k3 = 1.0;
  /// Weight of a pix2pix-style L1 reconstruction term on G, recon_weight * E|I_g(y) - I_r(y)|
  /// (all channels), added to L_G. Not in the paper: 0 in the paper-literal presets.
  double recon_weight = 0.0;
  /// R1 zero-centred gradient penalty on D's real images, r1_gamma / 2 * E||grad_I D_pro(I_r)||^2
  /// (Mescheder et al. 2018), added to L_D. Not in the paper: 0 = off.
  double r1_gamma = 0.0;

  // --- training data ---
  /// Geometry-densified training (not in the paper: 0 = off in every preset). Before training,
  /// `p2i bench` and `p2i train` add round(densify_ratio x training frames) views rendered by
  /// `densify_method` (a method of model/method_registry.h built over the training frames, e.g.
  /// "fusion" or "warp") at poses near the trajectory: a random training pose moved up to
  /// densify_offset_m in a random direction and turned up to densify_angle_deg about a random
  /// axis (model/densify.h). G then sees targets off the captured path, where the training frames
  /// alone leave it to interpolate. The trainer node does not densify (docs/MODEL.md).
  double densify_ratio = 0.0;
  double densify_offset_m = 0.15;
  double densify_angle_deg = 10.0;
  std::string densify_method = "fusion";
  /// Density-aware densifying (0 = off): of the round(densify_ratio x frames) candidate poses,
  /// those with a training frame within densify_min_gap_m and within densify_min_gap_deg of
  /// their orientation are dropped, so a dense capture gets fewer extra views than a sparse one
  /// (DensifyReport::skipped counts them).
  double densify_min_gap_m = 0.0;
  double densify_min_gap_deg = 5.0;
  /// Share of each training batch drawn from the captured frames when densified views are
  /// present (0 = off: every frame, captured or densified, equally likely). E.g. 0.5 keeps half
  /// of each batch real however many views densify_ratio adds, so a dense capture's frames are
  /// not seen a quarter as often at ratio 3. In [0, 1).
  double densify_real_share = 0.0;
  /// Phase-1 steps whose batches may hold densified views (-1 = every step of both phases). From
  /// phase-1 step densify_steps on, and through all of phase 2 (ENET), batches come from the
  /// captured frames only: the views teach G the geometry off the captured path, the last steps
  /// fit the captured frames' look. E.g. 5000 of 7000 phase-1 steps.
  int densify_steps = -1;

  // --- optimisation ---
  int batch_size = 16;
  int d_steps = 1;               ///< D updates per G update (each on its own batch)
  /// Decay of an exponential moving average of G's weights, updated after every G step (0 = off;
  /// the decay used at step t is min(g_ema, (1 + t) / (2 + t)): a running mean until then).
  /// When on, the average is the G that validation, phase 2, export and the synthesizer use
  /// (the raw G keeps training).
  double g_ema = 0.0;
  int steps_phase1 = 2000;
  int steps_phase2 = 1000;
  double lr_g = 2e-4;
  double lr_d = 2e-4;
  double lr_enet = 1e-3;
  /// Phase 1's last lr_decay_steps steps lower G's and D's learning rates linearly towards 0
  /// (pix2pix's schedule: constant, then linear decay; not in the paper). 0 = constant (default).
  /// A schedule key: on --resume the given config's value applies, like steps_phase1.
  int lr_decay_steps = 0;
  double beta1 = 0.0;
  double beta2 = 0.9;
  uint64_t seed = 1;
  double depth_max = 10.0;     ///< metres mapped to +1; 0 m (invalid) maps to -1
  int val_every = 200;         ///< steps between validation PSNR lines in the log
  int checkpoint_every = 200;  ///< steps between checkpoints (also the rollback points)
  double explode_factor = 50;  ///< a loss above factor x its running mean counts as divergence

  int Channels() const { return depth ? 4 : 3; }
  /// True while the Fourier band count is still to be chosen from the training poses.
  bool AutoFourierBands() const {
    return pose_encoding == "fourier" && fourier_bands == kAutoFourierBands;
  }
  /// Inputs of G's first layer: 7, or 7 (1 + 2 fourier_bands) with the Fourier encoding.
  /// Throws std::logic_error while the band count is "auto" (AutoFourierBands()).
  int PoseInputs() const;
  bool IsBaseline() const { return model == "cnn_baseline"; }
  /// The G width per stage that the schedule gives (4x4 first).
  std::vector<int> GeneratorWidths() const;

  /// Throws std::invalid_argument naming the bad field and the allowed values.
  void Validate() const;
  /// Unknown keys are errors naming key and source. Missing keys keep their defaults.
  static P2iConfig FromYamlString(const std::string& text, const std::string& source);
  static P2iConfig FromYamlFile(const std::string& path);
  /// The file with `KEY=VALUE` overrides applied in order (VALUE is YAML: 3, fusion, [1, 2]),
  /// as `p2i train --set`. A malformed override or an unknown key is an error naming it.
  static P2iConfig FromYamlFile(const std::string& path, const std::vector<std::string>& overrides);
  std::string ToYamlString() const;
};

}  // namespace p2i::model
