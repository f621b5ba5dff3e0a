# views/s through p2i_pool with 1 and 2 synthesizer workers (docs/POOL.md).
p2i_add_bench(pool_bench p2i_runtime p2i_scene p2i_convert p2i_util nlohmann_json::nlohmann_json)
add_dependencies(pool_bench p2i_pool p2i_synthesizer)
