# Transport benchmark: RGB-D pub/sub and service round trips over ipc and tcp (docs/RUNTIME.md).
p2i_add_bench(transport_bench p2i_runtime p2i_util nlohmann_json::nlohmann_json)
