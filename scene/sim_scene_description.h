/// @file sim_scene_description.h
/// @brief What a synthetic indoor scene contains (room, materials, objects, lights) and its
/// strict YAML format. The renderer (scene/sim_scene.h) takes this description, never the file.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace p2i::scene {

/// Procedural texture kinds. Every kind except kSolid carries fine (centimetre-scale) detail so
/// that blur and other quality losses in synthesised views are measurable.
enum class SimTexture { kSolid, kChecker, kTiles, kWood, kNoise, kPoster, kStripes };

/// A surface: albedo from a procedural texture over surface coordinates in metres, Lambertian
/// unless `specular` > 0 adds a view-dependent (Blinn-Phong) highlight of the lights' colour.
struct SimMaterial {
  std::string name;
  SimTexture texture = SimTexture::kSolid;
  Eigen::Vector3d color{0.7, 0.7, 0.7};   ///< linear RGB albedo in [0, 1]
  Eigen::Vector3d color2{0.3, 0.3, 0.3};  ///< second colour (checker, grout, grain, ...)
  double scale = 0.25;                    ///< metres per pattern period (tile, checker, cell)
  std::uint32_t seed = 0;                 ///< varies noise and poster patterns
  double specular = 0.0;   ///< highlight strength in [0, 2] (0 = Lambertian, view-independent)
  double shininess = 40.0;  ///< Blinn-Phong exponent in [1, 10000]: higher = smaller, sharper
};

enum class SimShape { kBox, kCylinder, kSphere };

/// One object. Boxes may be rotated about the world z axis (yaw); cylinders stand upright.
struct SimObject {
  std::string name;
  SimShape shape = SimShape::kBox;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< metres, world frame
  Eigen::Vector3d size{1.0, 1.0, 1.0};  ///< box: full extents x y z (before yaw)
  double radius = 0.5;                  ///< cylinder and sphere
  double height = 1.0;                  ///< cylinder
  double yaw_deg = 0.0;                 ///< box only
  int material = 0;                     ///< index into SimSceneDescription::materials
};

struct SimLight {
  enum class Type { kPoint, kDirectional };
  Type type = Type::kPoint;
  Eigen::Vector3d position{0.0, 0.0, 2.5};    ///< point light
  Eigen::Vector3d direction{0.0, 0.0, -1.0};  ///< directional light: where the light travels
  Eigen::Vector3d color{1.0, 1.0, 1.0};
  double intensity = 0.8;
  double range = 5.0;  ///< point light: attenuation 1 / (1 + (d / range)^2)
};

/// A room with z up: the floor is z = 0, the room spans x in [-sx/2, sx/2], y in [-sy/2, sy/2],
/// z in [0, sz]. This struct is a value type: thread-compatible.
struct SimSceneDescription {
  std::string name = "scene";
  Eigen::Vector3d room_size{6.0, 5.0, 2.8};
  int floor_material = 0;
  int ceiling_material = 0;
  /// Materials of the walls facing -x, +x, -y, +y (the walls AT x = -sx/2, x = +sx/2, ...).
  int wall_materials[4] = {0, 0, 0, 0};
  double ambient = 0.3;
  std::vector<SimMaterial> materials;
  std::vector<SimObject> objects;
  std::vector<SimLight> lights;

  /// Parses a scene YAML file (format in docs/SCENE.md). Throws std::runtime_error naming the
  /// file, line and key on unknown keys, missing keys, wrong types or invalid values.
  static SimSceneDescription FromYamlFile(const std::string& path);
  /// Same from text; `source` names the text in error messages.
  static SimSceneDescription FromYamlString(const std::string& text,
                                            const std::string& source = "<string>");

  /// Throws std::invalid_argument saying what is wrong (sizes, indices, finite values).
  void Validate() const;

  /// True when some material has a specular highlight.
  bool AnyViewDependent() const;
  /// A copy with every highlight removed (specular = 0): the Lambertian scene.
  SimSceneDescription Lambertian() const;

  Eigen::Vector3d RoomMin() const { return {-room_size.x() / 2, -room_size.y() / 2, 0.0}; }
  Eigen::Vector3d RoomMax() const { return {room_size.x() / 2, room_size.y() / 2, room_size.z()}; }
};

}  // namespace p2i::scene
