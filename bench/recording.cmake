# Recording / playback / Foxglove bridge benchmark (docs/RECORDING.md): runs `p2i record` and
# p2i_foxglove_bridge as child processes beside it.
p2i_add_bench(recording_bench p2i_recording p2i_convert p2i_runtime p2i_scene p2i_util nlohmann_json::nlohmann_json)
add_dependencies(recording_bench p2i p2i_foxglove_bridge)
