# P2I-NET training-step and inference benchmark (uses only model/'s torch-free headers).
p2i_add_bench(model_bench p2i_model p2i_scene p2i_util)
target_compile_definitions(model_bench PRIVATE P2I_SOURCE_DIR_BENCH="${PROJECT_SOURCE_DIR}")
