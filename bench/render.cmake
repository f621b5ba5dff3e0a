# Speed of the synthetic scene renderer (scene/sim_scene.h): bench/render_bench.cc.
p2i_add_bench(render_bench p2i_scene p2i_util)
