/// @file tsdf_volume.cc
/// @brief TsdfVolume on Open3D's tensor VoxelBlockGrid (float tsdf, weight and colour).
#include "fusion/tsdf_volume.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <vector>

#include <yaml-cpp/yaml.h>

#include <memory>
#include <string>
#include <unordered_map>

#include <open3d/core/Tensor.h>
#include <open3d/core/hashmap/HashMap.h>
#include <open3d/t/geometry/Geometry.h>
#include <open3d/t/geometry/Image.h>
#include <open3d/t/geometry/PointCloud.h>
#include <open3d/t/geometry/TensorMap.h>
#include <open3d/t/geometry/TriangleMesh.h>
// Open3D 0.16's VoxelBlockGrid::RayCast sizes its private fragment buffer (the range map's work
// list) to the previous call's exact need and drops every block whose fragments reach the end of
// the buffer (a ">=" check): the same view twice loses blocks, a bigger view loses many, and the
// first call on a small image gets a buffer of 0 (measured: 0 % then 65 % of the pixels of a
// plane hit). The buffer is a private member, so it is sized here before each raycast; only that
// class's access is opened (everything it includes is included above).
#define private public
#include <open3d/t/geometry/VoxelBlockGrid.h>
#undef private

#include "fusion/frustum.h"
#include "fusion/surface_mesh.h"
#include "fusion/tsdf_field.h"
#include "fusion/tsdf_integrate.h"
#include "scene/strict_yaml_reader.h"

namespace p2i::fusion {
namespace {

namespace core = open3d::core;
namespace tg = open3d::t::geometry;

/// Open3D 0.16 consults OMP_NUM_THREADS when it sizes its parallel loops; set it once (without
/// overriding a user's value) and set the count of the calling thread before each call.
void UseThreads(int threads) {
  static const bool env_set = [] {
    setenv("OMP_NUM_THREADS", "1", 0);
    return true;
  }();
  (void)env_set;
  omp_set_num_threads(threads);
}

/// Open3D's intrinsic of a camera. `shift` is added to the principal point: see IntegrationIntrinsic.
core::Tensor Intrinsic(const scene::CameraInfo& c, double shift = 0.0) {
  return core::Tensor::Init<double>(
      {{c.fx(), 0.0, c.cx() + shift}, {0.0, c.fy(), c.cy() + shift}, {0.0, 0.0, 1.0}});
}

/// The intrinsic Integrate is given. p2i (like OpenCV) puts pixel centres at integer coordinates,
/// and so does Open3D's RayCast (the ray of pixel (x, y) goes through (x, y)). Open3D 0.16's
/// Integrate, though, reads the depth pixel of a voxel projecting to (u, v) as (int(u), int(v)):
/// it truncates, so a pixel's depth lands half a pixel right of and below where it was measured
/// and the fused surface sits half a pixel off every raycast (on surfaces at an angle to the view
/// a depth bias of half a pixel's slope, at edges a misplaced silhouette). Shifting the principal
/// point by +0.5 turns the truncation into rounding: int(u + 0.5) is the nearest pixel centre.
core::Tensor IntegrationIntrinsic(const scene::CameraInfo& c) { return Intrinsic(c, 0.5); }

/// World-to-camera 4x4 (Open3D's extrinsic) of a camera-to-world pose.
core::Tensor Extrinsic(const scene::Pose& pose) {
  const Eigen::Matrix4d m = pose.Inverse().ToMatrix();
  std::vector<double> v(16);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) v[static_cast<size_t>(r * 4 + c)] = m(r, c);
  return core::Tensor(v, {4, 4}, core::Float64);
}

bool Bool(const scene::StrictYamlReader& r, const YAML::Node& n, const std::string& what) {
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    r.Fail(n, what + " must be true or false");
  }
  return false;
}

/// One pass of crack filling (TsdfOptions::crack_fill_passes) on a raycast. A pixel without a hit
/// whose valid 8-neighbours (at least 3) agree within 5 % is a crack: with a field, its own ray
/// is marched through the neighbours' depth range for the zero crossing; without one (or where
/// the march finds none) it takes the neighbours' mean depth. Normal and colour: their means.
void FillCracks(const TsdfField* field, const scene::Pose& pose, const scene::CameraInfo& camera,
                TsdfRaycast* r) {
  const cv::Mat depth = r->depth.clone();
  const cv::Mat normals = r->normals.clone();
  const cv::Mat colour = r->colour.clone();
  const Eigen::Matrix3f cw = pose.ToMatrix().block<3, 3>(0, 0).cast<float>();
  const Eigen::Vector3f origin = pose.translation().cast<float>();
  for (int v = 1; v + 1 < depth.rows; ++v) {
    for (int u = 1; u + 1 < depth.cols; ++u) {
      if (depth.at<float>(v, u) > 0.0f) continue;
      int n = 0;
      float zmin = 1e9f, zmax = 0.0f, zsum = 0.0f;
      cv::Vec3f nsum(0, 0, 0), csum(0, 0, 0);
      for (int dv = -1; dv <= 1; ++dv)
        for (int du = -1; du <= 1; ++du) {
          const float z = depth.at<float>(v + dv, u + du);
          if (!(z > 0.0f)) continue;
          ++n;
          zmin = std::min(zmin, z);
          zmax = std::max(zmax, z);
          zsum += z;
          nsum += normals.at<cv::Vec3f>(v + dv, u + du);
          csum += colour.at<cv::Vec3f>(v + dv, u + du);
        }
      if (n < 3 || zmax > 1.05f * zmin) continue;
      const float len = static_cast<float>(cv::norm(nsum));
      if (!(len > 1e-6f)) continue;
      float z = 0.0f;
      if (field) {
        const Eigen::Vector3f ray((u - camera.cx()) / camera.fx(), (v - camera.cy()) / camera.fy(), 1.0f);
        z = field->FindCrossing(origin, cw * ray, 0.97f * zmin, 1.03f * zmax);
      }
      r->depth.at<float>(v, u) = z > 0.0f ? z : zsum / n;
      r->normals.at<cv::Vec3f>(v, u) = nsum / len;
      r->colour.at<cv::Vec3f>(v, u) = csum / static_cast<float>(n);
    }
  }
}

}  // namespace

TsdfOptions TsdfOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  const scene::StrictYamlReader r(source);
  r.CheckKeys(node,
              {"voxel_size_m", "block_resolution", "initial_blocks", "trunc_voxels", "depth_min_m",
               "depth_max_m", "weight_threshold", "crack_fill_passes", "threads", "refine_hits", "surface",
               "integrator"},
              "tsdf options");
  TsdfOptions o;
  r.OptionalDouble(node, "voxel_size_m", "tsdf", &o.voxel_size_m);
  if (node["block_resolution"]) {
    const YAML::Node& b = node["block_resolution"];
    o.block_resolution = b.IsScalar() && b.Scalar() == "auto" ? 0 : r.Int(b, "block_resolution");
  }
  if (node["initial_blocks"]) o.initial_blocks = r.Int(node["initial_blocks"], "initial_blocks");
  r.OptionalDouble(node, "trunc_voxels", "tsdf", &o.trunc_voxels);
  r.OptionalDouble(node, "depth_min_m", "tsdf", &o.depth_min_m);
  r.OptionalDouble(node, "depth_max_m", "tsdf", &o.depth_max_m);
  r.OptionalDouble(node, "weight_threshold", "tsdf", &o.weight_threshold);
  if (node["crack_fill_passes"]) o.crack_fill_passes = r.Int(node["crack_fill_passes"], "crack_fill_passes");
  if (node["threads"]) o.threads = r.Int(node["threads"], "threads");
  if (node["refine_hits"]) o.refine_hits = Bool(r, node["refine_hits"], "refine_hits");
  if (node["surface"]) o.surface = r.String(node["surface"], "surface");
  if (node["integrator"]) o.integrator = r.String(node["integrator"], "integrator");
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    r.Fail(node, e.what());
  }
  return o;
}

void TsdfOptions::Validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("TsdfOptions." + what); };
  if (!(voxel_size_m > 0.0) || !std::isfinite(voxel_size_m)) fail("voxel_size_m must be > 0");
  if (block_resolution != 0 && (block_resolution < 2 || block_resolution > 64))
    fail("block_resolution must be auto (0) or in [2, 64], got " + std::to_string(block_resolution));
  if (initial_blocks < 1) fail("initial_blocks must be >= 1");
  if (!(trunc_voxels >= 1.0) || !std::isfinite(trunc_voxels)) fail("trunc_voxels must be >= 1");
  if (!(depth_min_m > 0.0)) fail("depth_min_m must be > 0");
  if (!(depth_max_m > depth_min_m) || !std::isfinite(depth_max_m))
    fail("depth_max_m must be finite and > depth_min_m");
  if (!(weight_threshold >= 0.0) || !std::isfinite(weight_threshold))
    fail("weight_threshold must be finite and >= 0");
  if (crack_fill_passes < 0) fail("crack_fill_passes must be >= 0");
  if (threads < 1) fail("threads must be >= 1");
  if (surface != "raycast" && surface != "mesh")
    fail("surface must be raycast or mesh, got '" + surface + "'");
  if (integrator != "p2i" && integrator != "open3d")
    fail("integrator must be p2i or open3d, got '" + integrator + "'");
}

namespace {

/// The width (m) of one pixel of `frames` at `depth_m`; infinite without a positive focal length.
double PixelWidthM(const scene::CameraInfo& frames, double depth_m) {
  const double f = std::min(frames.fx(), frames.fy());
  return f > 0.0 ? depth_m / f : std::numeric_limits<double>::infinity();
}

}  // namespace

TsdfOptions TsdfOptions::ForFrames(const scene::CameraInfo& frames) const {
  TsdfOptions o = *this;
  if (o.block_resolution != 0) return o;
  // The width of one pixel at the far end of the range: no wider than a voxel, and every voxel
  // of a surface's truncation band is crossed by some ray, so small blocks leave no gaps.
  o.block_resolution = PixelWidthM(frames, depth_max_m) <= voxel_size_m ? 8 : 16;
  return o;
}

std::string TsdfOptions::DescribeBlockChoice(const scene::CameraInfo& frames) const {
  char line[160];
  std::snprintf(line, sizeof(line),
                "blocks auto: %d^3 voxels (a frame pixel is %.1f cm wide at %.0f m, a voxel %.1f cm)",
                ForFrames(frames).block_resolution, 100.0 * PixelWidthM(frames, depth_max_m), depth_max_m,
                100.0 * voxel_size_m);
  return line;
}

namespace {

/// Open3D 0.16's ExtractTriangleMesh asserts (abort, not an exception) that a neighbour voxel's
/// linear index is > 0, but 0 is a valid index: voxel 0 of the block at buffer index 0. A surface
/// crossing the edge into that voxel aborts the process (seen in tests/refine on a 4 cm grid of
/// six frames). The mesh is therefore extracted from a copy whose buffer index 0 holds an empty
/// sentinel block far from everything (weight 0: no surface, no neighbour), then every block of
/// the grid. Costs a copy of the voxel data (~20-30 ms per 1000 blocks of 16^3) per extraction.
/// A copy of `grid`'s active blocks in a new grid with room for at least `capacity` blocks;
/// `sentinel` first puts an empty block far from everything at buffer index 0 (ExtractionCopy).
tg::VoxelBlockGrid CopyBlocks(tg::VoxelBlockGrid& grid, const TsdfOptions& o, int64_t capacity, bool sentinel) {
  core::HashMap map = grid.GetHashMap();
  const core::Tensor active = map.GetActiveIndices().To(core::Int64);
  const core::Tensor keys = map.GetKeyTensor().IndexGet({active}).Contiguous();
  const int64_t n = keys.GetLength();
  tg::VoxelBlockGrid copy({"tsdf", "weight", "color"}, {core::Float32, core::Float32, core::Float32},
                          {{1}, {1}, {3}}, static_cast<float>(o.voxel_size_m), o.block_resolution,
                          std::max(capacity, n + (sentinel ? 1 : 0)), core::Device("CPU:0"));
  core::HashMap cmap = copy.GetHashMap();
  const int64_t r3 = static_cast<int64_t>(o.block_resolution) * o.block_resolution * o.block_resolution;
  if (sentinel) {
    const int far = -(1 << 20);
    const auto [first, first_ok] = cmap.Activate(core::Tensor::Init<int>({{far, far, far}}));
    if (first.To(core::Int64).GetDataPtr<int64_t>()[0] != 0)
      throw std::runtime_error("TsdfVolume: the mesh extraction's sentinel block did not get buffer index 0");
  }
  if (n == 0) return copy;
  const auto [buf, ok] = cmap.Activate(keys);
  const core::Tensor dst = buf.To(core::Int64).Contiguous();
  const int64_t* dp = dst.GetDataPtr<int64_t>();
  const int64_t* sp = active.GetDataPtr<int64_t>();
  for (const auto& [name, channels] : {std::pair<const char*, int64_t>{"tsdf", 1}, {"weight", 1}, {"color", 3}}) {
    const float* from = grid.GetAttribute(name).GetDataPtr<float>();
    float* to = copy.GetAttribute(name).GetDataPtr<float>();
    const int64_t block = r3 * channels;
    if (sentinel) std::fill(to, to + block, 0.0f);  // weight 0
    for (int64_t i = 0; i < n; ++i) std::copy(from + sp[i] * block, from + (sp[i] + 1) * block, to + dp[i] * block);
  }
  return copy;
}

tg::VoxelBlockGrid ExtractionCopy(tg::VoxelBlockGrid& grid, const TsdfOptions& o) {
  return CopyBlocks(grid, o, 0, true);
}

}  // namespace

struct TsdfVolume::Impl {
  tg::VoxelBlockGrid grid;
  int64_t frames = 0;
  /// The grid's blocks for trilinear reads, built on the first raycast after a change (its
  /// pointers into the grid's arrays are valid until the next Integrate).
  std::unique_ptr<TsdfField> field;

  /// The field, built from the n block keys `kp` (x, y, z each) at buffer indices `ap` (the
  /// grid's active blocks, which the raycast has read already) unless it is still valid.
  const TsdfField& Field(const TsdfOptions& o, const int* kp, const int64_t* ap, int64_t n) {
    if (field) return *field;
    field = std::make_unique<TsdfField>(static_cast<float>(o.voxel_size_m), o.block_resolution,
                                        grid.GetAttribute("tsdf").GetDataPtr<float>(),
                                        grid.GetAttribute("weight").GetDataPtr<float>());
    for (int64_t i = 0; i < n; ++i) field->AddBlock(kp[3 * i], kp[3 * i + 1], kp[3 * i + 2], ap[i]);
    field->Seal();
    return *field;
  }

  /// The mesh of surface "mesh", extracted unless still valid (marching cubes over voxels with
  /// weight above the raycast's threshold; Open3D gives vertex normals and colours).
  std::unique_ptr<SurfaceMesh> mesh;
  const SurfaceMesh& Mesh(const TsdfOptions& o) {
    if (mesh) return *mesh;
    std::vector<Eigen::Vector3f> pos, nrm, col;
    std::vector<int64_t> tri;
    if (grid.GetHashMap().Size() > 0) {
      tg::VoxelBlockGrid safe = ExtractionCopy(grid, o);
      const tg::TriangleMesh m = safe.ExtractTriangleMesh(static_cast<float>(o.weight_threshold));
      const auto copy = [](const core::Tensor& t, std::vector<Eigen::Vector3f>* out) {
        const core::Tensor c = t.To(core::Float32).Contiguous();
        const float* p = c.GetDataPtr<float>();
        out->resize(static_cast<size_t>(c.GetLength()));
        for (size_t i = 0; i < out->size(); ++i) (*out)[i] = Eigen::Vector3f(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
      };
      if (m.HasVertexPositions() && m.HasTriangleIndices()) {
        copy(m.GetVertexPositions(), &pos);
        copy(m.GetVertexNormals(), &nrm);
        copy(m.GetVertexColors(), &col);
        const core::Tensor t = m.GetTriangleIndices().To(core::Int64).Contiguous();
        tri.assign(t.GetDataPtr<int64_t>(), t.GetDataPtr<int64_t>() + t.NumElements());
      }
    }
    mesh = std::make_unique<SurfaceMesh>(pos, nrm, col, tri);
    return *mesh;
  }
};

TsdfVolume::TsdfVolume(TsdfOptions options, Unallocated) : options_(options) {
  options_.Validate();
  if (options_.block_resolution == 0)
    throw std::invalid_argument("TsdfVolume: block_resolution auto must be resolved for the frames' "
                                "camera first (TsdfOptions::ForFrames)");
  impl_ = std::make_unique<Impl>();
}

TsdfVolume::TsdfVolume(TsdfOptions options) : TsdfVolume(options, Unallocated{}) {
  UseThreads(options_.threads);
  impl_->grid = tg::VoxelBlockGrid({"tsdf", "weight", "color"},
                                   {core::Float32, core::Float32, core::Float32}, {{1}, {1}, {3}},
                                   static_cast<float>(options_.voxel_size_m),
                                   options_.block_resolution, options_.initial_blocks,
                                   core::Device("CPU:0"));
}

TsdfVolume TsdfVolume::Clone() const {
  // Open3D touches every block of a grid's capacity when it allocates one, so the copy is made
  // for exactly the blocks it holds (it grows on demand, as any grid) and no empty grid of
  // initial_blocks is allocated first: with 16^3 blocks that empty grid alone was 164 MB.
  TsdfVolume v(options_, Unallocated{});
  UseThreads(options_.threads);
  v.impl_->grid = CopyBlocks(impl_->grid, options_, 1, false);
  v.impl_->frames = impl_->frames;
  return v;
}

TsdfVolume::~TsdfVolume() = default;
TsdfVolume::TsdfVolume(TsdfVolume&&) noexcept = default;
TsdfVolume& TsdfVolume::operator=(TsdfVolume&&) noexcept = default;

namespace {

/// TsdfOptions::integrator "p2i": VoxelBlockGrid::Integrate with the kernel of tsdf_integrate.h.
void IntegrateWithOwnKernel(tg::VoxelBlockGrid& grid, const TsdfOptions& options, const core::Tensor& block_coords,
                            const cv::Mat& depth, const cv::Mat& colour, const scene::CameraInfo& camera,
                            const core::Tensor& extrinsic) {
  // What VoxelBlockGrid::Integrate does before its kernel: activate the blocks (the hash map
  // grows here when they do not fit), then find every one's buffer index.
  core::HashMap& map = *grid.block_hashmap_;
  core::Tensor buf, mask;
  map.Activate(block_coords, buf, mask);
  map.Find(block_coords, buf, mask);
  std::vector<core::Tensor> values = map.GetValueTensors();  // tsdf, weight, color
  const core::Tensor keys = map.GetKeyTensor();
  VoxelBlocks g;
  g.resolution = options.block_resolution;
  g.voxel_size = static_cast<float>(options.voxel_size_m);
  g.sdf_trunc = g.voxel_size * static_cast<float>(options.trunc_voxels);
  g.keys = keys.GetDataPtr<int>();
  g.tsdf = values.at(0).GetDataPtr<float>();
  g.weight = values.at(1).GetDataPtr<float>();
  g.colour = values.at(2).GetDataPtr<float>();
  IntegrationFrame f;
  // 8-bit colour read through the floats OpenCV's conversion makes of each value: a quarter of
  // the bytes a float frame would take through the cache, and no conversion of the frame.
  static const cv::Mat colour_values = [] {
    cv::Mat bytes(1, 256, CV_8UC1), values;
    for (int v = 0; v < 256; ++v) bytes.at<std::uint8_t>(0, v) = static_cast<std::uint8_t>(v);
    bytes.convertTo(values, CV_32F, 1.0 / 255.0);
    return values;
  }();
  f.depth = depth.ptr<float>();
  f.colour = colour.ptr<std::uint8_t>();
  f.colour_values = colour_values.ptr<float>();
  f.width = depth.cols;
  f.height = depth.rows;
  const core::Tensor k = IntegrationIntrinsic(camera);  // what Open3D's kernel is given
  const double* kp = k.GetDataPtr<double>();
  f.fx = kp[0];
  f.cx = kp[2];
  f.fy = kp[4];
  f.cy = kp[5];
  const core::Tensor e = extrinsic.Contiguous();
  const double* ep = e.GetDataPtr<double>();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) f.extrinsic[i][j] = ep[4 * i + j];
  f.depth_max_m = static_cast<float>(options.depth_max_m);
  const core::Tensor indices = buf.To(core::Int32).Contiguous();
  IntegrateBlocks(g, indices.GetDataPtr<int>(), indices.GetLength(), f, options.threads);
}

}  // namespace

void TsdfVolume::Integrate(const scene::RgbdSample& frame, const scene::CameraInfo& camera) {
  scene::CheckFitsCamera(frame, camera, "TsdfVolume::Integrate: frame");
  UseThreads(options_.threads);
  impl_->field.reset();
  impl_->mesh.reset();
  cv::Mat depth = frame.depth.isContinuous() ? frame.depth : frame.depth.clone();
  const core::Tensor dt(depth.data, core::Float32, {depth.rows, depth.cols, 1});
  const tg::Image di(dt);
  const core::Tensor k = Intrinsic(camera), e = Extrinsic(frame.pose);
  const float trunc = static_cast<float>(options_.trunc_voxels);
  const float dmax = static_cast<float>(options_.depth_max_m);
  const core::Tensor blocks = impl_->grid.GetUniqueBlockCoordinates(di, k, e, 1.0f, dmax, trunc);
  if (blocks.GetLength() == 0) {
    ++impl_->frames;  // nothing valid in range: the frame adds nothing
    return;
  }
  if (options_.integrator == "open3d") {
    cv::Mat colour;
    frame.rgb.convertTo(colour, CV_32FC3, 1.0 / 255.0);
    const core::Tensor ct(colour.data, core::Float32, {colour.rows, colour.cols, 3});
    impl_->grid.Integrate(blocks, di, tg::Image(ct), IntegrationIntrinsic(camera), e, 1.0f, dmax, trunc);
  } else {
    const cv::Mat colour = frame.rgb.isContinuous() ? frame.rgb : frame.rgb.clone();
    IntegrateWithOwnKernel(impl_->grid, options_, blocks, depth, colour, camera, e);
  }
  ++impl_->frames;
}

namespace {

/// Keys (x, y, z per block) of the blocks whose bounding sphere can be in the view frustum, so
/// the raycast's range map covers only what this view can see.
std::vector<int> FrustumBlocks(const int* kp, int64_t n, const TsdfOptions& o, const Eigen::Matrix4d& wc,
                               const scene::CameraInfo& camera) {
  const int w = camera.image_width, h = camera.image_height;
  const double block = o.voxel_size_m * o.block_resolution;
  const double radius = block * std::sqrt(3.0) * 0.5;
  const Eigen::Matrix3d r = wc.block<3, 3>(0, 0);
  const Eigen::Vector3d t = wc.block<3, 1>(0, 3);
  std::vector<int> selected;
  selected.reserve(static_cast<size_t>(n) * 3);
  for (int64_t i = 0; i < n; ++i) {
    const Eigen::Vector3d centre((kp[3 * i] + 0.5) * block, (kp[3 * i + 1] + 0.5) * block,
                                 (kp[3 * i + 2] + 0.5) * block);
    if (!SphereMayBeInView(Eigen::Vector3d(r * centre + t), radius, 0.0, o.depth_max_m, camera.fx(),
                           camera.fy(), camera.cx(), camera.cy(), w, h))
      continue;
    selected.insert(selected.end(), {kp[3 * i], kp[3 * i + 1], kp[3 * i + 2]});
  }
  return selected;
}

/// Range map factor (ray start/end per tile of down x down pixels): Open3D's default 8, finer for
/// small images so that a tile does not span a large part of the view. It must divide both
/// sizes: otherwise Open3D 0.16 reads past the range map and RayCast hangs now and then (seen
/// at 80x60 with factor 3, a GOMP_parallel loop that never returns).
int RangeMapFactor(int w, int h) {
  int down = std::max(1, std::min(8, std::min(w, h) / 16));
  while (down > 1 && (w % down != 0 || h % down != 0)) --down;
  return down;
}

/// Open3D's raycast maps (depth, camera-frame normals, voxel colour) into `out`: hits only, the
/// depth moved onto the trilinear zero crossing when `field` is given, normals facing the camera.
void CopyHits(const float* dp, const float* np, const float* cp, const scene::Pose& pose,
              const scene::CameraInfo& camera, const TsdfField* field, TsdfRaycast* out) {
  const Eigen::Matrix3f rf = pose.Inverse().ToMatrix().block<3, 3>(0, 0).cast<float>();
  const Eigen::Matrix3f cw = pose.ToMatrix().block<3, 3>(0, 0).cast<float>();
  const Eigen::Vector3f origin = pose.translation().cast<float>();
  const int w = camera.image_width, h = camera.image_height;
  for (int v = 0; v < h; ++v) {
    float* drow = out->depth.ptr<float>(v);
    cv::Vec3f* nrow = out->normals.ptr<cv::Vec3f>(v);
    cv::Vec3f* crow = out->colour.ptr<cv::Vec3f>(v);
    for (int u = 0; u < w; ++u) {
      const size_t i = static_cast<size_t>(v) * w + u;
      float z = dp[i];
      if (!(z > 0.0f) || !std::isfinite(z)) continue;
      Eigen::Vector3f nc = rf * Eigen::Vector3f(np[3 * i], np[3 * i + 1], np[3 * i + 2]);
      const float len = nc.norm();
      if (!(len > 1e-6f)) continue;  // no gradient: not a usable surface
      nc /= len;
      const Eigen::Vector3f ray((u - camera.cx()) / camera.fx(), (v - camera.cy()) / camera.fy(), 1.0f);
      if (nc.dot(ray) > 0.0f) nc = -nc;  // face the camera
      if (field) z = field->RefineHit(origin, cw * ray, z);  // t along a ray with z = 1: z-depth
      drow[u] = z;
      nrow[u] = cv::Vec3f(nc.x(), nc.y(), nc.z());
      crow[u] = cv::Vec3f(std::min(1.0f, std::max(0.0f, cp[3 * i])),
                          std::min(1.0f, std::max(0.0f, cp[3 * i + 1])),
                          std::min(1.0f, std::max(0.0f, cp[3 * i + 2])));
    }
  }
}

}  // namespace

TsdfRaycast TsdfVolume::Raycast(const scene::Pose& pose, const scene::CameraInfo& camera,
                                const cv::Mat* only) {
  const int w = camera.image_width, h = camera.image_height;
  TsdfRaycast out;
  out.depth = cv::Mat::zeros(h, w, CV_32FC1);
  out.normals = cv::Mat::zeros(h, w, CV_32FC3);
  out.colour = cv::Mat::zeros(h, w, CV_32FC3);
  if (w <= 0 || h <= 0 || camera.fx() <= 0.0 || camera.fy() <= 0.0)
    throw std::invalid_argument("TsdfVolume::Raycast: the camera needs a positive size and focal length");
  UseThreads(options_.threads);
  core::HashMap map = impl_->grid.GetHashMap();
  if (map.Size() == 0) return out;
  if (options_.surface == "mesh") {
    impl_->Mesh(options_).Rasterize(pose, camera, static_cast<float>(options_.depth_min_m),
                                    static_cast<float>(options_.depth_max_m), &out, only);
    return out;
  }

  const core::Tensor active = map.GetActiveIndices().To(core::Int64);
  const core::Tensor keys = map.GetKeyTensor().IndexGet({active}).Contiguous();  // (N, 3) Int32
  const int64_t n = keys.GetLength();
  const int* kp = keys.GetDataPtr<int>();
  const std::vector<int> selected = FrustumBlocks(kp, n, options_, pose.Inverse().ToMatrix(), camera);
  if (selected.empty()) return out;
  const core::Tensor frustum(selected, {static_cast<int64_t>(selected.size() / 3), 3}, core::Int32);

  const core::Tensor k = Intrinsic(camera), e = Extrinsic(pose);
  const int down = RangeMapFactor(w, h);
  // Upper bound of the fragments (16 x 16 tiles of the range map) the frustum blocks can need,
  // plus one for Open3D's ">=" check (see the include above).
  const int64_t h_down = (h + down - 1) / down, w_down = (w + down - 1) / down;
  const int64_t per_block = ((h_down + 15) / 16 + 1) * ((w_down + 15) / 16 + 1);
  impl_->grid.fragment_buffer_ =
      core::Tensor({frustum.GetLength() * per_block + 1, 6}, core::Float32, core::Device("CPU:0"));
  auto result = impl_->grid.RayCast(frustum, k, e, w, h, {"depth", "normal", "color"}, 1.0f,
                                    static_cast<float>(options_.depth_min_m),
                                    static_cast<float>(options_.depth_max_m),
                                    static_cast<float>(options_.weight_threshold),
                                    static_cast<float>(options_.trunc_voxels), down);
  const core::Tensor depth = result["depth"].Contiguous();
  const core::Tensor normal = result["normal"].Contiguous();
  const core::Tensor colour = result["color"].Contiguous();
  const TsdfField* field =
      options_.refine_hits ? &impl_->Field(options_, kp, active.GetDataPtr<int64_t>(), n) : nullptr;
  CopyHits(depth.GetDataPtr<float>(), normal.GetDataPtr<float>(), colour.GetDataPtr<float>(), pose,
           camera, field, &out);
  for (int pass = 0; pass < options_.crack_fill_passes; ++pass) FillCracks(field, pose, camera, &out);
  return out;
}

void TsdfVolume::Prepare() {
  UseThreads(options_.threads);
  core::HashMap map = impl_->grid.GetHashMap();
  if (map.Size() == 0) return;
  if (options_.surface == "mesh") {
    impl_->Mesh(options_);
  } else if (options_.refine_hits) {
    const core::Tensor active = map.GetActiveIndices().To(core::Int64);
    const core::Tensor keys = map.GetKeyTensor().IndexGet({active}).Contiguous();
    impl_->Field(options_, keys.GetDataPtr<int>(), active.GetDataPtr<int64_t>(), keys.GetLength());
  }
}

TsdfStats TsdfVolume::Stats() const {
  TsdfStats s;
  s.frames = impl_->frames;
  s.blocks = impl_->grid.GetHashMap().Size();
  s.capacity_blocks = impl_->grid.GetHashMap().GetCapacity();
  const double voxels = std::pow(static_cast<double>(options_.block_resolution), 3.0);
  // tsdf (4 B) + weight (4 B) + colour (12 B) per voxel, plus the key (3 x int32) per block.
  s.memory_bytes = static_cast<double>(s.blocks) * (voxels * 20.0 + 12.0);
  s.block_volume_m3 = static_cast<double>(s.blocks) *
                      std::pow(options_.voxel_size_m * options_.block_resolution, 3.0);
  return s;
}

void TsdfVolume::Save(const std::string& path) const {
  // Open3D appends nothing when the name already ends in .npz; keep the suffix on the temp file.
  const std::string tmp = path + ".tmp.npz";
  impl_->grid.Save(tmp);
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error("TsdfVolume::Save: cannot rename " + tmp + " to " + path + ": " + ec.message());
}

TsdfVolume TsdfVolume::Load(const std::string& path, TsdfOptions options) {
  if (!std::filesystem::exists(path))
    throw std::runtime_error("TsdfVolume::Load: no file " + path);
  TsdfVolume v(options, Unallocated{});  // the loaded grid replaces any allocated here
  try {
    v.impl_->grid = tg::VoxelBlockGrid::Load(path);
  } catch (const std::exception& e) {
    throw std::runtime_error("TsdfVolume::Load: " + path + " is not a saved volume: " + e.what());
  }
  return v;
}

}  // namespace p2i::fusion
