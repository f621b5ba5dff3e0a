/// @file render_bench.cc
/// @brief Median time per frame of SimScene::Render on one thread at several resolutions, along
/// a small-office arm sweep. Prints a table and writes CSV.
///
/// Usage: render_bench [--scene small_office|large_office|FILE.yaml] [--frames N]
///                     [--csv render_bench.csv] [--sensor | --realistic]
///                     [--dump DIR]  (also writes the first frame of each size as PNG)
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "scene/sim_scene.h"
#include "scene/trajectory.h"
#include "util/heap_policy.h"

namespace {

// CPU time of this thread: on a shared machine it tells the renderer's own cost apart from
// waiting for a core (wall time is what a caller sees when it has a core to itself).
double ThreadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

p2i::scene::CameraInfo MakeCamera(int w, int h) {
  // 7-Scenes-like field of view (f = 585 at 640x480), scaled to the image width.
  const double f = 585.0 * w / 640.0;
  return p2i::scene::CameraInfo::Pinhole(w, h, f, f, (w - 1) / 2.0, (h - 1) / 2.0);
}

// The first frame of a size as PNG (RGB, depth in mm) for a look at what was timed.
void DumpFrame(const std::string& dump_dir, int w, int h, const p2i::scene::RgbdSample& sample) {
  const std::string stem = dump_dir + "/" + std::to_string(w) + "x" + std::to_string(h);
  cv::Mat bgr, depth_mm;
  cv::cvtColor(sample.rgb, bgr, cv::COLOR_RGB2BGR);
  sample.depth.convertTo(depth_mm, CV_16U, 1000.0);
  cv::imwrite(stem + "_rgb.png", bgr);
  cv::imwrite(stem + "_depth_mm.png", depth_mm);
}

// `frames` renders at w x h along the trajectory: the printed line and the CSV row.
void BenchSize(const p2i::scene::SimScene& scene,
               const std::vector<p2i::scene::StampedPose>& trajectory, const std::string& scene_name,
               int w, int h, int frames, const std::string& dump_dir, std::ofstream& csv) {
  const auto camera = MakeCamera(w, h);
  std::vector<double> ms, cpu_ms;
  double checksum = 0;
  for (int f = 0; f < frames; ++f) {
    const std::size_t index = (f * 7) % trajectory.size();
    const double c0 = ThreadCpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    // Along the trajectory: with --realistic the motion blur of the sweep's own motion.
    const auto sample = scene.RenderOnTrajectory(trajectory, index, camera);
    const auto t1 = std::chrono::steady_clock::now();
    cpu_ms.push_back(ThreadCpuMs() - c0);
    checksum += sample.depth.at<float>(h / 2, w / 2);
    if (f == 0 && !dump_dir.empty()) DumpFrame(dump_dir, w, h, sample);
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  double mean = 0;
  for (double m : ms) mean += m;
  mean /= ms.size();
  std::nth_element(ms.begin(), ms.begin() + ms.size() / 2, ms.end());
  const double median = ms[ms.size() / 2];
  std::nth_element(cpu_ms.begin(), cpu_ms.begin() + cpu_ms.size() / 2, cpu_ms.end());
  const double cpu_median = cpu_ms[cpu_ms.size() / 2];
  std::printf("%4dx%-5d %10.2f %10.2f %10.1f %10.2f %10.1f   (checksum %.3f)\n", w, h, median,
              mean, 1000.0 / median, cpu_median, 1000.0 / cpu_median, checksum);
  csv << scene_name << "," << w << "," << h << "," << frames << "," << median << "," << mean
      << "," << 1000.0 / median << "," << cpu_median << "," << 1000.0 / cpu_median << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (!p2i::util::ApplyHeapPolicyOrReport("render_bench")) return 2;  // P2I_HEAP
  std::string scene_name = "small_office", csv_path = "render_bench.csv";
  int frames = 60;
  std::string sensor;  // "" = exact, kinect, realistic
  std::string dump_dir;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--scene" && i + 1 < argc) {
      scene_name = argv[++i];
    } else if (a == "--frames" && i + 1 < argc) {
      frames = std::max(1, std::stoi(argv[++i]));
    } else if (a == "--csv" && i + 1 < argc) {
      csv_path = argv[++i];
    } else if (a == "--dump" && i + 1 < argc) {
      dump_dir = argv[++i];
    } else if (a == "--sensor") {
      sensor = "kinect";
    } else if (a == "--realistic") {
      sensor = "realistic";
    } else {
      std::cerr << "usage: render_bench [--scene NAME|FILE.yaml] [--frames N] [--csv FILE] "
                   "[--sensor | --realistic] [--dump DIR]\n";
      return 2;
    }
  }
  try {
    p2i::scene::SimScene scene =
        scene_name.size() > 5 && scene_name.substr(scene_name.size() - 5) == ".yaml"
            ? p2i::scene::SimScene::FromYamlFile(scene_name)
            : p2i::scene::SimScene::BuiltIn(scene_name);
    if (sensor == "kinect") scene.set_sensor_options(p2i::scene::SimSensorOptions::Kinect(1));
    if (sensor == "realistic") {
      scene.set_sensor_options(p2i::scene::SimSensorOptions::Realistic(1));
    }
    const auto trajectory = p2i::scene::GenerateArmSweep(p2i::scene::ArmSweepOptions());
    std::ofstream csv(csv_path);
    csv << "scene,width,height,frames,median_ms,mean_ms,fps,median_cpu_ms,cpu_fps\n";
    std::printf("scene %s, %d frames per size, one thread%s\n", scene_name.c_str(), frames,
                sensor.empty() ? "" : (", " + sensor + " sensor effects").c_str());
    std::printf("%10s %10s %10s %10s %10s %10s\n", "size", "median_ms", "mean_ms", "fps", "cpu_ms",
                "cpu_fps");
    const int sizes[][2] = {{640, 480}, {256, 256}, {128, 128}};
    for (const auto& s : sizes)
      BenchSize(scene, trajectory, scene_name, s[0], s[1], frames, dump_dir, csv);
    std::printf("wrote %s\n", csv_path.c_str());
  } catch (const std::exception& e) {
    std::cerr << "render_bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
