/// @file trajectory_io.cc
/// @brief TUM trajectory reading and atomic writing.
#include "scene/trajectory_io.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace p2i::scene {

std::vector<StampedPose> ParseTumTrajectory(const std::string& text, const std::string& source,
                                            TumStampOrder order) {
  std::vector<StampedPose> out;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();  // files written on Windows
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    StampedPose sp;
    try {
      sp.pose = Pose::FromTumLine(line, &sp.stamp);
    } catch (const std::exception& e) {
      throw std::runtime_error(source + ":" + std::to_string(line_no) + ": " + e.what() +
                               " (expected 'timestamp tx ty tz qx qy qz qw')");
    }
    if (order == TumStampOrder::kStrict && !out.empty() && !(sp.stamp > out.back().stamp)) {
      throw std::runtime_error(source + ":" + std::to_string(line_no) + ": timestamp " +
                               std::to_string(sp.stamp) + " is not after the previous one (" +
                               std::to_string(out.back().stamp) +
                               "); TUM trajectories must be sorted by time");
    }
    out.push_back(sp);
  }
  if (order == TumStampOrder::kSort) {
    std::stable_sort(out.begin(), out.end(), [](const StampedPose& a, const StampedPose& b) {
      return a.stamp < b.stamp;
    });
  }
  return out;
}

std::vector<StampedPose> ReadTumTrajectory(const std::string& path, TumStampOrder order) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open trajectory file");
  std::stringstream ss;
  ss << in.rdbuf();
  return ParseTumTrajectory(ss.str(), path, order);
}

std::string FormatTumTrajectory(const std::vector<StampedPose>& trajectory,
                                const std::string& comment) {
  std::ostringstream os;
  if (!comment.empty()) {
    std::istringstream lines(comment);
    std::string l;
    while (std::getline(lines, l)) os << "# " << l << "\n";
  }
  os << "# timestamp tx ty tz qx qy qz qw (camera-to-world, metres, seconds)\n";
  for (const auto& sp : trajectory) os << sp.pose.ToTumLine(sp.stamp) << "\n";
  return os.str();
}

void WriteTumTrajectory(const std::string& path, const std::vector<StampedPose>& trajectory,
                        const std::string& comment) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot write trajectory (is the folder there?)");
    out << FormatTumTrajectory(trajectory, comment);
    out.flush();
    if (!out) throw std::runtime_error(path + ": write failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot rename the temporary file into place");
  }
}

}  // namespace p2i::scene
