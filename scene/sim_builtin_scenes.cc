/// @file sim_builtin_scenes.cc
/// @brief GENERATED from scene/scenes/*.yaml: edit the YAML files, then regenerate this file
/// (python3 scene/scenes/embed_scenes.py); tests/scene/sim_scene_test.cc checks both agree.
#include "scene/sim_builtin_scenes.h"

#include <map>
#include <stdexcept>

namespace p2i::scene {
namespace {

// long-function: generated table of the scene files
const std::map<std::string, std::string>& Scenes() {
  static const auto* const kScenes = new std::map<std::string, std::string>{
      {"small_office", R"p2i_yaml(# Small office (6 m x 5 m x 2.8 m), like the smaller room of the P2I-NET paper's CP2V^2 dataset.
# World frame: z up, floor at z = 0, the room spans x in [-3, 3], y in [-2.5, 2.5].
# The centre (radius ~1.2 m around x = y = 0) and the arm zone (|x| < 1.2, y < -0.6) are kept
# free of furniture so the default trajectories fit. Format: docs/SCENE.md.
name: small_office
ambient: 0.3
room:
  size: [6.0, 5.0, 2.8]
  floor: floor_tiles
  ceiling: ceiling_tiles
  walls: [plaster_warm, plaster_warm, plaster_cool, plaster_cool]  # at -x, +x, -y, +y
materials:
  floor_tiles: {texture: tiles, color: [0.72, 0.68, 0.60], color2: [0.25, 0.24, 0.22], scale: 0.5}
  ceiling_tiles: {texture: tiles, color: [0.92, 0.92, 0.90], color2: [0.6, 0.6, 0.6], scale: 0.6}
  plaster_warm: {texture: noise, color: [0.86, 0.80, 0.70], color2: [0.70, 0.64, 0.55], scale: 0.4}
  plaster_cool: {texture: noise, color: [0.78, 0.82, 0.86], color2: [0.60, 0.65, 0.70], scale: 0.4}
  oak: {texture: wood, color: [0.80, 0.60, 0.38], color2: [0.52, 0.34, 0.18], scale: 0.3}
  walnut: {texture: wood, color: [0.50, 0.33, 0.20], color2: [0.28, 0.17, 0.10], scale: 0.25}
  metal: {texture: noise, color: [0.62, 0.64, 0.66], color2: [0.45, 0.47, 0.50], scale: 0.2}
  books: {texture: stripes, color: [0.70, 0.15, 0.12], color2: [0.15, 0.30, 0.60], scale: 0.06}
  screen: {texture: checker, color: [0.10, 0.12, 0.15], color2: [0.20, 0.35, 0.55], scale: 0.04}
  fabric: {texture: noise, color: [0.20, 0.30, 0.55], color2: [0.10, 0.15, 0.30], scale: 0.05}
  foliage: {texture: noise, color: [0.20, 0.55, 0.20], color2: [0.05, 0.25, 0.08], scale: 0.05}
  terracotta: {texture: stripes, color: [0.72, 0.38, 0.22], color2: [0.60, 0.30, 0.16], scale: 0.05}
  rug: {texture: checker, color: [0.65, 0.20, 0.18], color2: [0.85, 0.78, 0.62], scale: 0.2}
  globe: {texture: checker, color: [0.15, 0.35, 0.75], color2: [0.30, 0.65, 0.30], scale: 0.05}
  poster_a: {texture: poster, color: [0.95, 0.85, 0.20], color2: [0.10, 0.10, 0.40], scale: 0.2, seed: 11}
  poster_b: {texture: poster, color: [0.90, 0.30, 0.30], color2: [0.05, 0.40, 0.30], scale: 0.15, seed: 22}
  poster_c: {texture: poster, color: [0.95, 0.95, 0.95], color2: [0.10, 0.10, 0.10], scale: 0.25, seed: 33}
  poster_d: {texture: poster, color: [0.30, 0.70, 0.95], color2: [0.60, 0.10, 0.50], scale: 0.18, seed: 44}
lights:
  - {type: point, position: [0.0, 0.3, 2.6], intensity: 0.75, range: 4.0}
  - {type: directional, direction: [0.3, -0.5, -1.0], intensity: 0.25}
objects:
  # Desk against the +y wall, with a monitor.
  - {name: desk_a_top, shape: box, center: [-1.0, 2.05, 0.74], size: [1.6, 0.8, 0.04], material: oak}
  - {name: desk_a_left, shape: box, center: [-1.76, 2.05, 0.36], size: [0.04, 0.76, 0.72], material: oak}
  - {name: desk_a_right, shape: box, center: [-0.24, 2.05, 0.36], size: [0.04, 0.76, 0.72], material: oak}
  - {name: monitor, shape: box, center: [-1.0, 2.3, 1.0], size: [0.56, 0.04, 0.38], material: screen}
  # Desk against the +x wall, with a globe.
  - {name: desk_b_top, shape: box, center: [2.6, 0.5, 0.74], size: [0.8, 1.6, 0.04], material: walnut}
  - {name: desk_b_near, shape: box, center: [2.6, -0.26, 0.36], size: [0.76, 0.04, 0.72], material: walnut}
  - {name: desk_b_far, shape: box, center: [2.6, 1.26, 0.36], size: [0.76, 0.04, 0.72], material: walnut}
  - {name: globe, shape: sphere, center: [2.6, 1.0, 0.88], radius: 0.12, material: globe}
  # Bookshelf against the -x wall.
  - {name: shelf, shape: box, center: [-2.82, 0.2, 0.9], size: [0.36, 1.2, 1.8], material: oak}
  - {name: books_low, shape: box, center: [-2.62, 0.2, 0.55], size: [0.06, 1.0, 0.26], material: books}
  - {name: books_mid, shape: box, center: [-2.62, 0.2, 1.0], size: [0.06, 1.0, 0.24], material: books}
  - {name: books_high, shape: box, center: [-2.62, 0.25, 1.45], size: [0.06, 0.9, 0.22], material: books}
  - {name: cabinet, shape: box, center: [2.65, -1.8, 0.5], size: [0.6, 0.9, 1.0], material: metal}
  # Posters and a door: flat boxes on the walls.
  - {name: poster_a, shape: box, center: [0.8, 2.49, 1.6], size: [1.0, 0.02, 0.7], material: poster_a}
  - {name: poster_b, shape: box, center: [2.99, 0.4, 1.7], size: [0.02, 0.9, 0.6], material: poster_b}
  - {name: poster_c, shape: box, center: [-2.99, -1.5, 1.5], size: [0.02, 0.8, 1.0], material: poster_c}
  - {name: poster_d, shape: box, center: [1.5, -2.49, 1.5], size: [0.8, 0.02, 0.6], material: poster_d}
  - {name: door, shape: box, center: [-1.9, -2.48, 1.0], size: [0.9, 0.04, 2.0], material: walnut}
  - {name: rug, shape: box, center: [0.0, 0.3, 0.005], size: [2.0, 1.4, 0.01], material: rug}
  # Chair, plant, bin and a floor lamp.
  - {name: chair_seat, shape: box, center: [-1.0, 1.45, 0.46], size: [0.46, 0.46, 0.06], yaw_deg: 15, material: fabric}
  - {name: chair_stem, shape: cylinder, center: [-1.0, 1.45, 0.22], radius: 0.04, height: 0.44, material: metal}
  - {name: plant_pot, shape: cylinder, center: [-2.5, 2.1, 0.25], radius: 0.2, height: 0.5, material: terracotta}
  - {name: plant, shape: sphere, center: [-2.5, 2.1, 0.8], radius: 0.35, material: foliage}
  - {name: bin, shape: cylinder, center: [1.6, 2.1, 0.2], radius: 0.15, height: 0.4, material: metal}
  - {name: lamp_pole, shape: cylinder, center: [2.55, 2.15, 0.8], radius: 0.03, height: 1.6, material: metal}
  - {name: lamp_shade, shape: sphere, center: [2.55, 2.15, 1.7], radius: 0.18, material: ceiling_tiles}
)p2i_yaml"},
      {"large_office", R"p2i_yaml(# Large office (10 m x 8 m x 3 m), like the larger room of the P2I-NET paper's CP2V^2 dataset:
# a row of workstations, shelves, a meeting corner, pillars and posters. The varnished floor,
# white desks, screens, metal and the whiteboard are glossy (specular: a highlight that moves with
# the view), so the scene is not purely Lambertian.
# World frame: z up, floor at z = 0, the room spans x in [-5, 5], y in [-4, 4].
# The centre (radius ~1.2 m around x = y = 0) and the arm zone (|x| < 1.2, -2.5 < y < -0.6) are
# kept free of furniture so the default trajectories fit. Format: docs/SCENE.md.
name: large_office
ambient: 0.28
room:
  size: [10.0, 8.0, 3.0]
  floor: floor_wood
  ceiling: ceiling_tiles
  walls: [plaster_warm, plaster_cool, plaster_cool, plaster_warm]  # at -x, +x, -y, +y
materials:
  floor_wood: {texture: wood, color: [0.70, 0.52, 0.34], color2: [0.48, 0.32, 0.20], scale: 0.35, specular: 0.8, shininess: 20}
  ceiling_tiles: {texture: tiles, color: [0.92, 0.92, 0.90], color2: [0.6, 0.6, 0.6], scale: 0.6}
  plaster_warm: {texture: noise, color: [0.88, 0.82, 0.72], color2: [0.70, 0.64, 0.55], scale: 0.5}
  plaster_cool: {texture: noise, color: [0.80, 0.84, 0.86], color2: [0.62, 0.66, 0.70], scale: 0.5}
  desk_white: {texture: noise, color: [0.92, 0.92, 0.90], color2: [0.80, 0.80, 0.78], scale: 0.1, specular: 0.6, shininess: 60}
  oak: {texture: wood, color: [0.80, 0.60, 0.38], color2: [0.52, 0.34, 0.18], scale: 0.3}
  walnut: {texture: wood, color: [0.50, 0.33, 0.20], color2: [0.28, 0.17, 0.10], scale: 0.25}
  metal: {texture: noise, color: [0.62, 0.64, 0.66], color2: [0.45, 0.47, 0.50], scale: 0.2, specular: 1.0, shininess: 40}
  concrete: {texture: noise, color: [0.66, 0.66, 0.64], color2: [0.45, 0.45, 0.44], scale: 0.15}
  books_a: {texture: stripes, color: [0.70, 0.15, 0.12], color2: [0.15, 0.30, 0.60], scale: 0.06}
  books_b: {texture: stripes, color: [0.85, 0.70, 0.20], color2: [0.20, 0.50, 0.25], scale: 0.05}
  screen: {texture: checker, color: [0.10, 0.12, 0.15], color2: [0.20, 0.35, 0.55], scale: 0.04, specular: 1.0, shininess: 120}
  fabric: {texture: noise, color: [0.20, 0.30, 0.55], color2: [0.10, 0.15, 0.30], scale: 0.05}
  fabric_red: {texture: noise, color: [0.60, 0.15, 0.15], color2: [0.30, 0.06, 0.06], scale: 0.05}
  foliage: {texture: noise, color: [0.20, 0.55, 0.20], color2: [0.05, 0.25, 0.08], scale: 0.05}
  terracotta: {texture: stripes, color: [0.72, 0.38, 0.22], color2: [0.60, 0.30, 0.16], scale: 0.05}
  carpet: {texture: checker, color: [0.30, 0.32, 0.40], color2: [0.45, 0.47, 0.55], scale: 0.25}
  whiteboard: {texture: checker, color: [0.96, 0.96, 0.96], color2: [0.88, 0.90, 0.92], scale: 0.1, specular: 0.8, shininess: 80}
  poster_a: {texture: poster, color: [0.95, 0.85, 0.20], color2: [0.10, 0.10, 0.40], scale: 0.2, seed: 101}
  poster_b: {texture: poster, color: [0.90, 0.30, 0.30], color2: [0.05, 0.40, 0.30], scale: 0.15, seed: 102}
  poster_c: {texture: poster, color: [0.95, 0.95, 0.95], color2: [0.10, 0.10, 0.10], scale: 0.25, seed: 103}
  poster_d: {texture: poster, color: [0.30, 0.70, 0.95], color2: [0.60, 0.10, 0.50], scale: 0.18, seed: 104}
  poster_e: {texture: poster, color: [0.95, 0.60, 0.20], color2: [0.20, 0.20, 0.60], scale: 0.12, seed: 105}
  poster_f: {texture: poster, color: [0.60, 0.90, 0.60], color2: [0.40, 0.10, 0.10], scale: 0.22, seed: 106}
lights:
  - {type: point, position: [-2.0, 0.5, 2.9], intensity: 0.6, range: 5.0}
  - {type: point, position: [2.5, -0.5, 2.9], intensity: 0.5, range: 5.0}
objects:
  # Four workstations along the +y wall.
  - {name: ws1_top, shape: box, center: [-3.6, 3.4, 0.74], size: [1.4, 0.8, 0.04], material: desk_white}
  - {name: ws1_side, shape: box, center: [-4.28, 3.4, 0.36], size: [0.04, 0.76, 0.72], material: desk_white}
  - {name: ws1_screen, shape: box, center: [-3.6, 3.65, 1.0], size: [0.56, 0.04, 0.38], material: screen}
  - {name: ws2_top, shape: box, center: [-1.4, 3.4, 0.74], size: [1.4, 0.8, 0.04], material: desk_white}
  - {name: ws2_side, shape: box, center: [-2.08, 3.4, 0.36], size: [0.04, 0.76, 0.72], material: desk_white}
  - {name: ws2_screen, shape: box, center: [-1.4, 3.65, 1.0], size: [0.56, 0.04, 0.38], material: screen}
  - {name: ws3_top, shape: box, center: [0.8, 3.4, 0.74], size: [1.4, 0.8, 0.04], material: oak}
  - {name: ws3_side, shape: box, center: [0.12, 3.4, 0.36], size: [0.04, 0.76, 0.72], material: oak}
  - {name: ws3_screen, shape: box, center: [0.8, 3.65, 1.0], size: [0.56, 0.04, 0.38], material: screen}
  - {name: ws4_top, shape: box, center: [3.0, 3.4, 0.74], size: [1.4, 0.8, 0.04], material: oak}
  - {name: ws4_side, shape: box, center: [3.68, 3.4, 0.36], size: [0.04, 0.76, 0.72], material: oak}
  - {name: ws4_screen, shape: box, center: [3.0, 3.65, 1.0], size: [0.56, 0.04, 0.38], material: screen}
  - {name: chair1_seat, shape: box, center: [-3.6, 2.7, 0.46], size: [0.46, 0.46, 0.06], yaw_deg: -10, material: fabric}
  - {name: chair1_stem, shape: cylinder, center: [-3.6, 2.7, 0.22], radius: 0.04, height: 0.44, material: metal}
  - {name: chair3_seat, shape: box, center: [0.8, 2.7, 0.46], size: [0.46, 0.46, 0.06], yaw_deg: 20, material: fabric_red}
  - {name: chair3_stem, shape: cylinder, center: [0.8, 2.7, 0.22], radius: 0.04, height: 0.44, material: metal}
  # Shelves along the -x wall.
  - {name: shelf1, shape: box, center: [-4.8, -1.0, 1.0], size: [0.4, 1.4, 2.0], material: walnut}
  - {name: shelf1_books_a, shape: box, center: [-4.57, -1.0, 0.6], size: [0.06, 1.2, 0.26], material: books_a}
  - {name: shelf1_books_b, shape: box, center: [-4.57, -1.0, 1.1], size: [0.06, 1.2, 0.24], material: books_b}
  - {name: shelf1_books_c, shape: box, center: [-4.57, -0.95, 1.6], size: [0.06, 1.1, 0.22], material: books_a}
  - {name: shelf2, shape: box, center: [-4.8, 1.0, 1.0], size: [0.4, 1.4, 2.0], material: walnut}
  - {name: shelf2_books_a, shape: box, center: [-4.57, 1.0, 0.6], size: [0.06, 1.2, 0.26], material: books_b}
  - {name: shelf2_books_b, shape: box, center: [-4.57, 1.05, 1.1], size: [0.06, 1.1, 0.24], material: books_a}
  # Cabinets along the +x wall.
  - {name: cabinet1, shape: box, center: [4.7, -2.8, 0.6], size: [0.6, 0.9, 1.2], material: metal}
  - {name: cabinet2, shape: box, center: [4.7, -1.8, 0.6], size: [0.6, 0.9, 1.2], material: metal}
  - {name: cabinet3, shape: box, center: [4.7, 2.0, 0.45], size: [0.6, 1.2, 0.9], material: oak}
  # Meeting corner (-x, -y) with a round table and stools.
  - {name: table_top, shape: cylinder, center: [-3.2, -2.8, 0.73], radius: 0.6, height: 0.04, material: oak}
  - {name: table_leg, shape: cylinder, center: [-3.2, -2.8, 0.36], radius: 0.06, height: 0.7, material: metal}
  - {name: stool1, shape: cylinder, center: [-2.3, -2.6, 0.23], radius: 0.2, height: 0.46, material: fabric_red}
  - {name: stool2, shape: cylinder, center: [-3.4, -1.9, 0.23], radius: 0.2, height: 0.46, material: fabric}
  - {name: carpet, shape: box, center: [-3.2, -2.8, 0.005], size: [2.2, 2.0, 0.01], material: carpet}
  # Pillars.
  - {name: pillar1, shape: cylinder, center: [-2.5, 0.0, 1.5], radius: 0.25, height: 3.0, material: concrete}
  - {name: pillar2, shape: cylinder, center: [2.5, 0.8, 1.5], radius: 0.25, height: 3.0, material: concrete}
  # Posters, whiteboard and doors on the walls.
  - {name: poster_a, shape: box, center: [-2.5, 3.99, 1.8], size: [1.0, 0.02, 0.7], material: poster_a}
  - {name: poster_b, shape: box, center: [2.0, 3.99, 1.9], size: [0.9, 0.02, 0.6], material: poster_b}
  - {name: poster_c, shape: box, center: [4.99, 0.3, 1.6], size: [0.02, 1.0, 0.8], material: poster_c}
  - {name: poster_d, shape: box, center: [-4.99, -2.8, 1.6], size: [0.02, 0.8, 0.6], material: poster_d}
  - {name: poster_e, shape: box, center: [2.8, -3.99, 1.6], size: [0.8, 0.02, 1.0], material: poster_e}
  - {name: poster_f, shape: box, center: [-4.99, 2.6, 1.5], size: [0.02, 0.7, 0.9], material: poster_f}
  - {name: whiteboard, shape: box, center: [-0.2, -3.98, 1.4], size: [1.8, 0.03, 1.0], material: whiteboard}
  - {name: door, shape: box, center: [4.97, -0.6, 1.05], size: [0.04, 1.0, 2.1], material: walnut}
  # Plants, bins and a globe.
  - {name: plant1_pot, shape: cylinder, center: [4.4, 3.5, 0.25], radius: 0.2, height: 0.5, material: terracotta}
  - {name: plant1, shape: sphere, center: [4.4, 3.5, 0.8], radius: 0.35, material: foliage}
  - {name: plant2_pot, shape: cylinder, center: [-4.5, -3.6, 0.25], radius: 0.2, height: 0.5, material: terracotta}
  - {name: plant2, shape: sphere, center: [-4.5, -3.6, 0.8], radius: 0.35, material: foliage}
  - {name: bin, shape: cylinder, center: [-0.4, 3.5, 0.2], radius: 0.15, height: 0.4, material: metal}
  - {name: globe, shape: sphere, center: [4.7, 2.0, 1.05], radius: 0.15, material: poster_c}
)p2i_yaml"},
  };
  return *kScenes;
}

}  // namespace

std::vector<std::string> BuiltInSceneNames() {
  return {"small_office", "large_office"};
}

const std::string& BuiltInSceneYaml(const std::string& name) {
  const auto it = Scenes().find(name);
  if (it == Scenes().end()) {
    throw std::invalid_argument("unknown built-in scene '" + name + "' (known: small_office, large_office)");
  }
  return it->second;
}

}  // namespace p2i::scene
