/// @file sim_scene_description.cc
/// @brief Strict YAML parsing and validation of synthetic scene descriptions.
#include "scene/sim_scene_description.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "scene/strict_yaml_reader.h"

namespace p2i::scene {
namespace {

std::uint32_t HashName(const std::string& s) {
  std::uint32_t h = 2166136261u;  // FNV-1a: stable across platforms, unlike std::hash
  for (unsigned char c : s) h = (h ^ c) * 16777619u;
  return h;
}

SimTexture ParseTexture(const StrictYamlReader& r, const YAML::Node& node) {
  static const std::map<std::string, SimTexture> kNames = {
      {"solid", SimTexture::kSolid},    {"checker", SimTexture::kChecker},
      {"tiles", SimTexture::kTiles},    {"wood", SimTexture::kWood},
      {"noise", SimTexture::kNoise},    {"poster", SimTexture::kPoster},
      {"stripes", SimTexture::kStripes}};
  const std::string name = r.String(node, "texture");
  const auto it = kNames.find(name);
  if (it == kNames.end()) {
    r.Fail(node, "unknown texture '" + name +
                     "' (use solid, checker, tiles, wood, noise, poster or stripes)");
  }
  return it->second;
}

SimMaterial ParseMaterial(const StrictYamlReader& r, const YAML::Node& key,
                          const YAML::Node& node) {
  SimMaterial m;
  m.name = key.as<std::string>();
  const std::string what = "material '" + m.name + "'";
  r.CheckKeys(node, {"texture", "color", "color2", "scale", "seed", "specular", "shininess"}, what);
  if (node["texture"]) m.texture = ParseTexture(r, node["texture"]);
  r.OptionalVec3(node, "color", what, &m.color);
  r.OptionalVec3(node, "color2", what, &m.color2);
  r.OptionalDouble(node, "scale", what, &m.scale);
  r.OptionalDouble(node, "specular", what, &m.specular);
  r.OptionalDouble(node, "shininess", what, &m.shininess);
  m.seed = HashName(m.name);
  if (node["seed"]) m.seed = static_cast<std::uint32_t>(r.Double(node["seed"], what + ".seed"));
  return m;
}

// Material name -> index into SimSceneDescription::materials.
class MaterialNames {
 public:
  explicit MaterialNames(const StrictYamlReader& r) : r_(r) {}
  void Add(const YAML::Node& key, const std::string& name, int index) {
    if (index_.count(name)) r_.Fail(key, "duplicate material '" + name + "'");
    index_[name] = index;
  }
  // The index of the material `node` names; fails naming `what` when it is not defined.
  int Lookup(const YAML::Node& node, const std::string& what) const {
    const std::string name = r_.String(node, what);
    const auto it = index_.find(name);
    if (it == index_.end()) {
      r_.Fail(node, what + ": unknown material '" + name + "' (define it under materials:)");
    }
    return it->second;
  }

 private:
  const StrictYamlReader& r_;
  std::map<std::string, int> index_;
};

MaterialNames ReadMaterials(const StrictYamlReader& r, const YAML::Node& root,
                            SimSceneDescription* d) {
  MaterialNames names(r);
  const YAML::Node materials = r.Require(root, "materials", "scene");
  r.CheckMap(materials, "materials");
  for (const auto& kv : materials) {
    const SimMaterial m = ParseMaterial(r, kv.first, kv.second);
    names.Add(kv.first, m.name, static_cast<int>(d->materials.size()));
    d->materials.push_back(m);
  }
  return names;
}

void ReadRoom(const StrictYamlReader& r, const MaterialNames& materials, const YAML::Node& root,
              SimSceneDescription* d) {
  const YAML::Node room = r.Require(root, "room", "scene");
  r.CheckKeys(room, {"size", "floor", "ceiling", "walls"}, "room");
  d->room_size = r.Vec3(r.Require(room, "size", "room"), "room.size");
  d->floor_material = materials.Lookup(r.Require(room, "floor", "room"), "room.floor");
  d->ceiling_material = materials.Lookup(r.Require(room, "ceiling", "room"), "room.ceiling");
  const YAML::Node walls = r.Require(room, "walls", "room");
  if (walls.IsSequence()) {
    if (walls.size() != 4) r.Fail(walls, "room.walls must be one material or a list of 4");
    for (int i = 0; i < 4; ++i) d->wall_materials[i] = materials.Lookup(walls[i], "room.walls");
  } else {
    const int m = materials.Lookup(walls, "room.walls");
    for (int& w : d->wall_materials) w = m;
  }
}

SimLight ParseLight(const StrictYamlReader& r, const YAML::Node& ln) {
  SimLight l;
  r.CheckKeys(ln, {"type", "position", "direction", "color", "intensity", "range"}, "light");
  const std::string type = r.String(r.Require(ln, "type", "light"), "light.type");
  if (type == "point") {
    l.type = SimLight::Type::kPoint;
    l.position = r.Vec3(r.Require(ln, "position", "point light"), "light.position");
    if (ln["direction"]) r.Fail(ln["direction"], "a point light has no direction");
  } else if (type == "directional") {
    l.type = SimLight::Type::kDirectional;
    l.direction = r.Vec3(r.Require(ln, "direction", "directional light"), "light.direction");
    if (ln["position"]) r.Fail(ln["position"], "a directional light has no position");
  } else {
    r.Fail(ln["type"], "unknown light type '" + type + "' (use point or directional)");
  }
  r.OptionalVec3(ln, "color", "light", &l.color);
  r.OptionalDouble(ln, "intensity", "light", &l.intensity);
  r.OptionalDouble(ln, "range", "light", &l.range);
  return l;
}

void ReadLights(const StrictYamlReader& r, const YAML::Node& root, SimSceneDescription* d) {
  if (!root["lights"]) return;
  const YAML::Node lights = root["lights"];
  if (!lights.IsSequence()) r.Fail(lights, "lights must be a list");
  for (const auto& ln : lights) d->lights.push_back(ParseLight(r, ln));
}

SimObject ParseObject(const StrictYamlReader& r, const MaterialNames& materials,
                      const YAML::Node& on) {
  SimObject o;
  r.CheckMap(on, "object");
  const std::string shape = r.String(r.Require(on, "shape", "object"), "object.shape");
  o.name = on["name"] ? r.String(on["name"], "object.name") : shape;
  const std::string what = "object '" + o.name + "'";
  o.center = r.Vec3(r.Require(on, "center", what), what + ".center");
  o.material = materials.Lookup(r.Require(on, "material", what), what + ".material");
  if (shape == "box") {
    o.shape = SimShape::kBox;
    r.CheckKeys(on, {"name", "shape", "center", "size", "yaw_deg", "material"}, what);
    o.size = r.Vec3(r.Require(on, "size", what), what + ".size");
    r.OptionalDouble(on, "yaw_deg", what, &o.yaw_deg);
  } else if (shape == "cylinder") {
    o.shape = SimShape::kCylinder;
    r.CheckKeys(on, {"name", "shape", "center", "radius", "height", "material"}, what);
    o.radius = r.Double(r.Require(on, "radius", what), what + ".radius");
    o.height = r.Double(r.Require(on, "height", what), what + ".height");
  } else if (shape == "sphere") {
    o.shape = SimShape::kSphere;
    r.CheckKeys(on, {"name", "shape", "center", "radius", "material"}, what);
    o.radius = r.Double(r.Require(on, "radius", what), what + ".radius");
  } else {
    r.Fail(on["shape"], "unknown shape '" + shape + "' (use box, cylinder or sphere)");
  }
  return o;
}

void ReadObjects(const StrictYamlReader& r, const MaterialNames& materials, const YAML::Node& root,
                 SimSceneDescription* d) {
  if (!root["objects"]) return;
  const YAML::Node objects = root["objects"];
  if (!objects.IsSequence()) r.Fail(objects, "objects must be a list");
  for (const auto& on : objects) d->objects.push_back(ParseObject(r, materials, on));
}

}  // namespace

SimSceneDescription SimSceneDescription::FromYamlFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open scene file");
  std::stringstream ss;
  ss << in.rdbuf();
  return FromYamlString(ss.str(), path);
}

SimSceneDescription SimSceneDescription::FromYamlString(const std::string& text,
                                                        const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(source + ":" + std::to_string(e.mark.line + 1) +
                             ": YAML syntax error: " + e.msg);
  }
  const StrictYamlReader r(source);
  r.CheckKeys(root, {"name", "room", "ambient", "materials", "lights", "objects"}, "scene");

  SimSceneDescription d;
  if (root["name"]) d.name = r.String(root["name"], "name");
  r.OptionalDouble(root, "ambient", "scene", &d.ambient);
  // Materials first: room and objects refer to them by name.
  const MaterialNames materials = ReadMaterials(r, root, &d);
  ReadRoom(r, materials, root, &d);
  ReadLights(r, root, &d);
  ReadObjects(r, materials, root, &d);
  try {
    d.Validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(source + ": " + e.what());
  }
  return d;
}

void SimSceneDescription::Validate() const {
  const auto fail = [](const std::string& m) { throw std::invalid_argument(m); };
  if (!(room_size.minCoeff() > 0.0) || !room_size.allFinite()) {
    fail("room size must be three positive numbers (metres)");
  }
  if (materials.empty()) fail("a scene needs at least one material");
  const int nm = static_cast<int>(materials.size());
  const auto check_index = [&](int i, const std::string& what) {
    if (i < 0 || i >= nm) fail(what + ": material index out of range");
  };
  check_index(floor_material, "floor");
  check_index(ceiling_material, "ceiling");
  for (int w : wall_materials) check_index(w, "walls");
  if (!(ambient >= 0.0 && ambient <= 2.0)) fail("ambient must be in [0, 2]");
  for (const auto& m : materials) {
    if (!(m.scale > 0.0)) fail("material '" + m.name + "': scale must be > 0");
    if (m.color.minCoeff() < 0.0 || m.color.maxCoeff() > 1.0 || m.color2.minCoeff() < 0.0 ||
        m.color2.maxCoeff() > 1.0) {
      fail("material '" + m.name + "': colours are RGB in [0, 1]");
    }
    if (!(m.specular >= 0.0 && m.specular <= 2.0)) {
      fail("material '" + m.name + "': specular must be in [0, 2] (got " +
           std::to_string(m.specular) + ")");
    }
    if (!(m.shininess >= 1.0 && m.shininess <= 10000.0)) {
      fail("material '" + m.name + "': shininess must be in [1, 10000] (got " +
           std::to_string(m.shininess) + ")");
    }
  }
  for (const auto& o : objects) {
    check_index(o.material, "object '" + o.name + "'");
    if (!o.center.allFinite()) fail("object '" + o.name + "': center must be finite");
    if (o.shape == SimShape::kBox && !(o.size.minCoeff() > 0.0)) {
      fail("object '" + o.name + "': box size must be positive");
    }
    if (o.shape != SimShape::kBox && !(o.radius > 0.0)) {
      fail("object '" + o.name + "': radius must be > 0");
    }
    if (o.shape == SimShape::kCylinder && !(o.height > 0.0)) {
      fail("object '" + o.name + "': height must be > 0");
    }
  }
  // The renderer's id buffer is 16-bit (6 room faces + objects).
  if (objects.size() > 30000) fail("at most 30000 objects");
  if (lights.size() > 4) fail("at most 4 lights (the renderer budget is one or two)");
  for (const auto& l : lights) {
    if (!(l.intensity >= 0.0)) fail("light intensity must be >= 0");
    if (!(l.range > 0.0)) fail("light range must be > 0");
    if (l.type == SimLight::Type::kDirectional && !(l.direction.norm() > 0.0)) {
      fail("directional light needs a non-zero direction");
    }
  }
}

bool SimSceneDescription::AnyViewDependent() const {
  for (const auto& m : materials) {
    if (m.specular > 0.0) return true;
  }
  return false;
}

SimSceneDescription SimSceneDescription::Lambertian() const {
  SimSceneDescription d = *this;
  for (auto& m : d.materials) m.specular = 0.0;
  return d;
}

}  // namespace p2i::scene
