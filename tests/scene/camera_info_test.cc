/// @file camera_info_test.cc
/// @brief CameraInfo: ROS YAML IO, validation, scaling/cropping, and every file in calib/.
#include "scene/camera_info.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>

#include <catch2/catch.hpp>

#include "tests/test_paths.h"

using p2i::scene::CameraInfo;
namespace fs = std::filesystem;

namespace {

const char* kTumFr1 = R"(image_width: 640
image_height: 480
camera_name: tum_fr1
camera_matrix:
  rows: 3
  cols: 3
  data: [517.3, 0, 318.6, 0, 516.5, 255.3, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [0.2624, -0.9531, -0.0054, 0.0026, 1.1633]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
projection_matrix:
  rows: 3
  cols: 4
  data: [517.3, 0, 318.6, 0, 0, 516.5, 255.3, 0, 0, 0, 1, 0]
)";

// Replaces the first occurrence of `from` in `text` (the test fails if it is absent).
std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  REQUIRE(pos != std::string::npos);
  return text.replace(pos, from.size(), to);
}

std::string ErrorOf(const std::string& yaml, const std::string& source = "cam.yaml") {
  try {
    CameraInfo::FromYamlString(yaml, source);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// Projects a camera-frame point with K (no distortion).
Eigen::Vector2d Project(const CameraInfo& c, const Eigen::Vector3d& p) {
  const Eigen::Vector3d h = c.K() * p;
  return h.head<2>() / h.z();
}

}  // namespace

TEST_CASE("CameraInfo reads every field of a ROS camera_info file", "[unit]") {
  const CameraInfo c = CameraInfo::FromYamlString(kTumFr1, "fr1.yaml");
  CHECK(c.camera_name == "tum_fr1");
  CHECK(c.image_width == 640);
  CHECK(c.image_height == 480);
  CHECK(c.fx() == 517.3);
  CHECK(c.fy() == 516.5);
  CHECK(c.cx() == 318.6);
  CHECK(c.cy() == 255.3);
  CHECK(c.distortion_model == "plumb_bob");
  REQUIRE(c.distortion_coefficients.size() == 5);
  CHECK(c.distortion_coefficients[0] == 0.2624);
  CHECK(c.distortion_coefficients[4] == 1.1633);
  CHECK(c.projection_matrix[5] == 516.5);
  CHECK(c.projection_matrix[6] == 255.3);
  CHECK(c.projection_matrix[10] == 1.0);
  const Eigen::Matrix3d k = c.K();
  CHECK(k(0, 0) == 517.3);
  CHECK(k(1, 2) == 255.3);
  CHECK(k(2, 2) == 1.0);
  CHECK(k(1, 0) == 0.0);
}

TEST_CASE("CameraInfo YAML write/read round trip is lossless", "[unit]") {
  CameraInfo c = CameraInfo::FromYamlString(kTumFr1);
  c.camera_name = "yes";  // would become a bool if written unquoted
  c.camera_matrix[2] = 1.0 / 3.0 + 300.0;  // needs all 17 digits
  const CameraInfo back = CameraInfo::FromYamlString(c.ToYamlString());
  CHECK(back.equals(c, 0.0));
  CHECK(back.camera_name == "yes");

  const fs::path path = fs::temp_directory_path() /
                        ("p2i_camera_info_test_" + std::to_string(::getpid()) + ".yaml");
  c.ToYamlFile(path.string());
  CHECK(CameraInfo::FromYamlFile(path.string()).equals(c, 0.0));
  // The atomic write leaves no temporary file behind.
  CHECK_FALSE(fs::exists(path.string() + ".tmp." + std::to_string(::getpid())));
  fs::remove(path);
}

TEST_CASE("CameraInfo fills P = [K|0], R = I and zero D when those keys are absent", "[unit]") {
  const std::string minimal =
      "image_width: 100\nimage_height: 50\n"
      "camera_matrix: {rows: 3, cols: 3, data: [80, 0, 49.5, 0, 90, 24.5, 0, 0, 1]}\n";
  const CameraInfo c = CameraInfo::FromYamlString(minimal);
  CHECK(c.equals(CameraInfo::Pinhole(100, 50, 80, 90, 49.5, 24.5, "camera")));
}

TEST_CASE("CameraInfo unknown and missing keys name the key and the file", "[unit]") {
  const std::string typo = ErrorOf(
      Replace(kTumFr1, "distortion_coefficients:", "distortion_coefficents:"), "calib/x.yaml");
  CHECK_THAT(typo, Catch::Contains("distortion_coefficents"));
  CHECK_THAT(typo, Catch::Contains("calib/x.yaml:9:"));  // line of the misspelt key

  const std::string nested = ErrorOf(Replace(kTumFr1, "  rows: 1\n", "  row: 1\n"));
  CHECK_THAT(nested, Catch::Contains("distortion_coefficients.row"));
  CHECK_THAT(nested, Catch::Contains("cam.yaml"));

  const std::string missing =
      ErrorOf("image_height: 480\ncamera_matrix: {rows: 3, cols: 3, data: [1,0,0,0,1,0,0,0,1]}\n");
  CHECK_THAT(missing, Catch::Contains("image_width"));
  CHECK_THAT(missing, Catch::Contains("cam.yaml"));
}

TEST_CASE("CameraInfo rejects wrong matrix sizes and bad values", "[unit]") {
  // 2 rows declared for K.
  CHECK_THAT(ErrorOf(Replace(kTumFr1, "  rows: 3\n  cols: 3\n  data: [517.3",
                             "  rows: 2\n  cols: 3\n  data: [517.3")),
             Catch::Contains("camera_matrix"));
  // 8 values for a 3x3 K.
  CHECK_THAT(ErrorOf(Replace(kTumFr1, "255.3, 0, 0, 1]", "255.3, 0, 0]")),
             Catch::Contains("camera_matrix.data"));
  // D count not matching the model.
  CHECK_THAT(ErrorOf(Replace(Replace(kTumFr1, "cols: 5", "cols: 4"), "-0.0054, 0.0026, 1.1633",
                             "-0.0054, 0.0026")),
             Catch::Contains("5 coefficients"));
  CHECK_THAT(ErrorOf(Replace(kTumFr1, "data: [517.3, 0, 318.6", "data: [-517.3, 0, 318.6")),
             Catch::Contains("focal"));
  CHECK_THAT(ErrorOf(Replace(kTumFr1, "data: [517.3, 0, 318.6", "data: [517.3, 0, 700.0")),
             Catch::Contains("principal point"));
  CHECK_THAT(ErrorOf(Replace(kTumFr1, "data: [517.3, 0, 318.6", "data: [.nan, 0, 318.6")),
             Catch::Contains("non-finite"));
  CHECK_THAT(ErrorOf(Replace(kTumFr1, "image_width: 640", "image_width: abc")),
             Catch::Contains("image_width"));
  CHECK_THAT(ErrorOf(Replace(kTumFr1, "plumb_bob", "fisheye_xyz")),
             Catch::Contains("fisheye_xyz"));
  CHECK_THROWS_AS(CameraInfo::FromYamlFile("/nonexistent/cam.yaml"), std::runtime_error);

  CameraInfo c = CameraInfo::Pinhole(640, 480, 500, 500, 320, 240);
  CHECK_NOTHROW(c.Validate());
  c.image_height = 0;
  CHECK_THROWS_AS(c.Validate(), std::invalid_argument);
  c = CameraInfo::Pinhole(640, 480, 500, 500, 320, -3);
  CHECK_THROWS_AS(c.Validate(), std::invalid_argument);
  c = CameraInfo::Pinhole(640, 480, 500, 500, 320, 240);
  c.projection_matrix[3] = std::numeric_limits<double>::infinity();
  CHECK_THROWS_AS(c.Validate(), std::invalid_argument);
  // Writing refuses invalid calibrations (the file could never be read back).
  CHECK_THROWS(c.ToYamlFile("/tmp/p2i_never_written.yaml"));
}

TEST_CASE("CameraInfo::Scaled follows the pixel-centre convention of cv::resize", "[unit]") {
  const CameraInfo c = CameraInfo::Pinhole(640, 480, 525, 525, 319.5, 239.5, "sim");
  const CameraInfo half = c.Scaled(320, 240);
  CHECK(half.image_width == 320);
  CHECK(half.image_height == 240);
  CHECK(half.fx() == Approx(262.5));
  CHECK(half.fy() == Approx(262.5));
  // The exact image centre stays the exact image centre: (319.5 + 0.5) / 2 - 0.5 = 159.5.
  CHECK(half.cx() == Approx(159.5));
  CHECK(half.cy() == Approx(119.5));
  CHECK(half.projection_matrix[0] == Approx(262.5));
  CHECK(half.projection_matrix[2] == Approx(159.5));
  CHECK(half.projection_matrix[6] == Approx(119.5));
  CHECK(half.distortion_coefficients == c.distortion_coefficients);

  // Anisotropic: 640x480 -> 128x128, sx = 0.2, sy = 4/15.
  const CameraInfo sq = CameraInfo::Pinhole(640, 480, 500, 600, 300, 200).Scaled(128, 128);
  CHECK(sq.fx() == Approx(100.0));
  CHECK(sq.fy() == Approx(160.0));
  CHECK(sq.cx() == Approx((300.0 + 0.5) * 0.2 - 0.5));
  CHECK(sq.cy() == Approx((200.0 + 0.5) * 128.0 / 480.0 - 0.5));

  // A 3D point lands where the resized pixel grid puts it.
  const Eigen::Vector3d p(0.3, -0.2, 2.0);
  const Eigen::Vector2d u = Project(c, p), v = Project(half, p);
  CHECK(v.x() == Approx((u.x() + 0.5) * 0.5 - 0.5));
  CHECK(v.y() == Approx((u.y() + 0.5) * 0.5 - 0.5));
  CHECK_THROWS_AS(c.Scaled(0, 10), std::invalid_argument);
}

TEST_CASE("CameraInfo::Cropped shifts the principal point by the crop origin", "[unit]") {
  const CameraInfo c = CameraInfo::Pinhole(640, 480, 585, 585, 320, 240);
  const CameraInfo crop = c.Cropped(80, 10, 480, 400);
  CHECK(crop.image_width == 480);
  CHECK(crop.image_height == 400);
  CHECK(crop.fx() == 585.0);
  CHECK(crop.cx() == 240.0);
  CHECK(crop.cy() == 230.0);
  CHECK(crop.projection_matrix[2] == 240.0);
  CHECK(crop.projection_matrix[6] == 230.0);
  const Eigen::Vector3d p(0.1, 0.4, 3.0);
  CHECK((Project(c, p) - Project(crop, p) - Eigen::Vector2d(80, 10)).norm() < 1e-9);
  CHECK_THROWS_AS(c.Cropped(200, 0, 480, 480), std::invalid_argument);  // 680 > 640
  CHECK_THROWS_AS(c.Cropped(-1, 0, 10, 10), std::invalid_argument);
}

TEST_CASE("CameraInfo::equals compares every field within the tolerance", "[unit]") {
  const CameraInfo a = CameraInfo::FromYamlString(kTumFr1);
  CameraInfo b = a;
  CHECK(a.equals(b));
  b.camera_matrix[0] += 1e-6;
  CHECK_FALSE(a.equals(b, 1e-9));
  CHECK(a.equals(b, 1e-5));
  b = a;
  b.distortion_coefficients[2] = 0.0;
  CHECK_FALSE(a.equals(b));
  b = a;
  b.projection_matrix[3] = -10.0;
  CHECK_FALSE(a.equals(b));
  b = a;
  b.camera_name = "other";
  CHECK_FALSE(a.equals(b));
}

TEST_CASE("Every calibration file in calib/ loads and validates", "[unit]") {
  const fs::path dir = fs::path(p2i::testing::SourceDir()) / "calib";
  int count = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".yaml") continue;
    INFO(entry.path().string());
    const CameraInfo c = CameraInfo::FromYamlFile(entry.path().string());
    CHECK(c.camera_name == entry.path().stem().string());
    // The file round-trips through our writer.
    CHECK(CameraInfo::FromYamlString(c.ToYamlString()).equals(c, 0.0));
    ++count;
  }
  CHECK(count >= 6);

  const auto load = [&](const char* name) {
    return CameraInfo::FromYamlFile((dir / name).string());
  };
  CHECK(load("sim.yaml").equals(CameraInfo::Pinhole(640, 480, 525, 525, 319.5, 239.5, "sim")));
  CHECK(load("seven_scenes_kinect.yaml")
            .equals(CameraInfo::Pinhole(640, 480, 585, 585, 320, 240, "seven_scenes_kinect")));
  CHECK(load("study_room.yaml").fx() == Approx(570.342).margin(1e-3));
  const CameraInfo fr2 = load("tum_fr2.yaml");
  CHECK(fr2.fx() == 520.9);
  CHECK(fr2.fy() == 521.0);
  CHECK(fr2.cx() == 325.1);
  CHECK(fr2.cy() == 249.7);
  CHECK(fr2.distortion_coefficients ==
        std::vector<double>{0.2312, -0.7849, -0.0033, -0.0001, 0.9172});
  const CameraInfo fr3 = load("tum_fr3.yaml");
  CHECK(fr3.fy() == 539.2);
  CHECK(fr3.distortion_coefficients == std::vector<double>(5, 0.0));
}
