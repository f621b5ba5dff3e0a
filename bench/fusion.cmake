# Speed and memory of the fusion method (TSDF integration, render with and without the hit and
# learned refinements, MB per m^3): bench/fusion_bench.cc.
p2i_add_bench(fusion_bench p2i_methods p2i_fusion p2i_scene p2i_util nlohmann_json::nlohmann_json yaml-cpp)
