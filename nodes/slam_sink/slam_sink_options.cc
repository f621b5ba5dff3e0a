/// @file slam_sink_options.cc
/// @brief SlamSinkOptions YAML parsing and validation; the node's parameters.
#include "nodes/slam_sink/slam_sink_options.h"

#include <functional>
#include <map>
#include <stdexcept>

#include "nodes/runtime/option_error.h"

namespace p2i::slam_sink {

SlamSinkOptions SlamSinkOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  SlamSinkOptions o;
  if (!node || node.IsNull()) return o;
  if (!node.IsMap()) {
    throw std::runtime_error("SlamSinkOptions: " + source + " must be a YAML mapping");
  }
  using Setter = std::function<void(const YAML::Node&)>;
  const std::map<std::string, Setter> setters = {
      {"out_dir", [&](const YAML::Node& v) { o.writer.out_dir = v.as<std::string>(); }},
      {"append", [&](const YAML::Node& v) { o.writer.append = v.as<bool>(); }},
      {"fsync", [&](const YAML::Node& v) { o.writer.fsync = v.as<bool>(); }},
      {"write_associations",
       [&](const YAML::Node& v) { o.writer.write_associations = v.as<bool>(); }},
      {"png_compression", [&](const YAML::Node& v) { o.writer.png_compression = v.as<int>(); }},
      {"depth_scale", [&](const YAML::Node& v) { o.writer.depth_scale = v.as<double>(); }},
      {"check", [&](const YAML::Node& v) { o.check = v.as<bool>(); }},
      {"policy", [&](const YAML::Node& v) { o.policy = v.as<std::string>(); }},
      {"write_real", [&](const YAML::Node& v) { o.write_real = v.as<bool>(); }},
      {"odometry_method", [&](const YAML::Node& v) { o.checker.method = v.as<std::string>(); }},
      {"max_translation_error_m",
       [&](const YAML::Node& v) { o.checker.max_translation_error_m = v.as<double>(); }},
      {"max_rotation_error_deg",
       [&](const YAML::Node& v) { o.checker.max_rotation_error_deg = v.as<double>(); }},
      {"min_coverage", [&](const YAML::Node& v) { o.checker.min_coverage = v.as<double>(); }},
      {"min_valid_depth_fraction",
       [&](const YAML::Node& v) { o.checker.min_valid_depth_fraction = v.as<double>(); }},
      {"min_depth_m", [&](const YAML::Node& v) { o.checker.min_depth_m = v.as<double>(); }},
      {"max_depth_m", [&](const YAML::Node& v) { o.checker.max_depth_m = v.as<double>(); }},
      {"max_baseline_m", [&](const YAML::Node& v) { o.checker.max_baseline_m = v.as<double>(); }},
      {"max_baseline_deg",
       [&](const YAML::Node& v) { o.checker.max_baseline_deg = v.as<double>(); }},
  };
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    const auto it = setters.find(key);
    if (it == setters.end()) {
      throw std::runtime_error("SlamSinkOptions: unknown key '" + key + "' in " + source +
                               " (see docs/SLAM_SINK.md for the keys)");
    }
    try {
      it->second(kv.second);
    } catch (const YAML::Exception& e) {
      throw std::runtime_error("SlamSinkOptions: bad value for '" + key + "' in " + source +
                               ": " + e.what());
    }
  }
  o.Validate();
  return o;
}

void SlamSinkOptions::Validate() const {
  writer.Validate();
  checker.Validate();
  runtime::CheckOption(policy == "flag" || policy == "drop", "slam_sink", "policy", policy,
                       "be flag or drop",
                       "policy:=flag writes failing frames, marked; policy:=drop does not write them");
}

SlamSinkOptions SlamSinkNodeOptions::SinkDefaults() {
  SlamSinkOptions o;
  o.writer.out_dir = "slam_sequence";
  return o;
}

SlamSinkNodeOptions SlamSinkNodeOptions::FromParameters(runtime::Parameters& p) {
  SlamSinkNodeOptions n;  // the defaults, written once in the field initialisers
  SlamSinkOptions& o = n.sink;
  o.writer.out_dir = p.Declare<std::string>("out_dir", o.writer.out_dir,
                                            "folder of the TUM RGB-D sequence (created)");
  o.writer.append =
      p.Declare<bool>("append", o.writer.append, "append to an existing sequence in out_dir");
  o.writer.fsync = p.Declare<bool>("fsync", o.writer.fsync, "fsync every image and index line");
  o.writer.png_compression =
      p.Declare<int>("png_compression", o.writer.png_compression, "PNG compression 0..9");
  o.writer.write_associations = p.Declare<bool>("write_associations", o.writer.write_associations,
                                                "write associations.txt (ORB-SLAM format)");
  o.check = p.Declare<bool>("check", o.check, "check synthetic views with RGB-D odometry");
  o.policy =
      p.Declare<std::string>("policy", o.policy, "failing views: flag (write, mark) | drop");
  o.write_real = p.Declare<bool>("write_real", o.write_real, "write frames received on real_topic");
  o.checker.method = p.Declare<std::string>("odometry_method", o.checker.method,
                                            "rgbd_icp | icp | rgbd (OpenCV rgbd module)");
  o.checker.max_translation_error_m = p.Declare<double>(
      "max_translation_error_m", o.checker.max_translation_error_m, "check threshold (m)");
  o.checker.max_rotation_error_deg = p.Declare<double>(
      "max_rotation_error_deg", o.checker.max_rotation_error_deg, "check threshold (deg)");
  o.checker.min_coverage = p.Declare<double>("min_coverage", o.checker.min_coverage,
                                             "views below this coverage fail");
  o.checker.min_valid_depth_fraction =
      p.Declare<double>("min_valid_depth_fraction", o.checker.min_valid_depth_fraction,
                        "views with fewer valid depth pixels fail");
  o.checker.min_depth_m =
      p.Declare<double>("min_depth_m", o.checker.min_depth_m, "odometry range");
  o.checker.max_depth_m =
      p.Declare<double>("max_depth_m", o.checker.max_depth_m, "odometry range");
  o.checker.max_baseline_m = p.Declare<double>("max_baseline_m", o.checker.max_baseline_m,
                                               "larger motions are not verified");
  o.checker.max_baseline_deg = p.Declare<double>("max_baseline_deg", o.checker.max_baseline_deg,
                                                 "larger rotations are not verified");
  n.camera_info_file = p.Declare<std::string>("camera_info_file", n.camera_info_file,
                                              "ROS camera_info YAML of the views");
  n.views_topic = p.Declare<std::string>("views_topic", n.views_topic, "View topic");
  n.real_topic = p.Declare<std::string>("real_topic", n.real_topic,
                                        "RgbdFrame topic of real frames ('' = off)");
  n.camera_info_topic =
      p.Declare<std::string>("camera_info_topic", n.camera_info_topic,
                             "CameraInfo topic used without camera_info_file");
  n.summary_period = p.Declare<double>("summary_period", n.summary_period,
                                       "rewrite summary.json every N s (0 = at exit)");
  return n;
}

}  // namespace p2i::slam_sink
