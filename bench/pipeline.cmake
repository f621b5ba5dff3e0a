# End-to-end serving benchmark: request-to-view latency and views/s through the p2i_synthesizer
# process, with and without a p2i_trainer process (docs/SYNTHESIZER.md). Runs the p2i,
# p2i_synthesizer and p2i_trainer executables beside it.
p2i_add_bench(pipeline_bench p2i_runtime p2i_scene p2i_convert p2i_util nlohmann_json::nlohmann_json)
target_compile_definitions(pipeline_bench PRIVATE P2I_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
add_dependencies(pipeline_bench p2i p2i_synthesizer p2i_trainer)
