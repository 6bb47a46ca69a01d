"""The numba kernels each scenario compiles, in order of first use (:mod:`swarm_envs._compile._first_run`).

Written by ``python -m swarm_envs._compile._kernel_record``; do not edit. ``KERNELS``: (module, function,
argument types) of kernels called from Python; ``SCENARIOS``: (task class, platform) -> (index into
KERNELS, process seconds its compile took on the recording machine) in order of first use."""

NUMBA_VERSION = '0.68.1'

KERNELS = [
    ('swarm_envs.sensing.exchange_kernels', 'roll_tables', ('int64[1C]', 'int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[3C]', 'float64[3C]', 'int64[2C]', 'int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[3C]', 'float64[3C]', 'int64[2C]', 'int64')),
    ('swarm_envs.sensing.exchange_kernels', 'encode_tables', ('int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[1C]', 'int64[1C]', 'int64', 'int64', 'int64', 'int64')),
    ('swarm_envs.comm.kernels', 'build_frames', ('int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'int64[1C]', 'int64', 'int64', 'bool', 'int64', 'int64[1C]', 'int64', 'int64', 'bool[2C]')),
    ('swarm_envs.comm.draws', '_generator_list', ('generator',)),
    ('swarm_envs.comm.draws', '_draw_copies_nb', ('list[generator]', 'int64', 'int64', 'int64', 'float64', 'int64', 'uint32[1C]', 'float32[1C]', 'float32[1C]', 'float32', 'float32')),
    ('swarm_envs.ir.pair_kernels', 'directed_pairs_kernel', ('int64[2C]', 'float64[2C]', 'float64[1C]', 'float64[1C]', 'float64[1C]')),
    ('swarm_envs.ir.pair_kernels', 'neighbour_csr_kernel', ('float64[2C]', 'int64[2C]', 'float64')),
    ('swarm_envs.ir.occluder_kernels', 'occluders_kernel', ('float64[2C]', 'float64', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]')),
    ('swarm_envs.ir.occluder_kernels', 'occluder_frames_kernel', ('float64[2C]', 'float64[1C]', 'float64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]')),
    ('swarm_envs.ir.gain_kernels', '_gains_chunk', ('int64', 'int64', 'float64[3C]', 'float64[2C]', 'int64[1C]', 'float64[2C]', 'float64[2C]', 'float64[2C,ro]', 'float64[1C,ro]', 'float64[2C,ro]', 'float64[1C,ro]', 'int64', 'float64[1C]', 'float64', 'int64[1C]', 'float64[2C]', 'float64', 'bool', 'int64[1C]', 'int64[1C]', 'float64[3C,ro]', 'float64[3C,ro]')),
    ('swarm_envs.ir.pair_kernels', 'select_links_kernel', ('int64[1C]', 'int64[1C]', 'int64[1C]', 'float64[2C]', 'float64[1C]', 'float64[1C]')),
    ('swarm_envs.sensing.range_bearing_kernels', 'merge_readings', ('int64[1C]', 'float64[2C]', 'int64[2C]', 'int64', 'int64[1C]', 'float64[2C]', 'int64[2C]')),
    ('swarm_envs.comm.kernels', 'link_tables', ('int64', 'int64[1C]', 'int64[1C]', 'float64[3C]', 'float64', 'float64[1C]', 'float64', 'float64')),
    ('swarm_envs.comm.kernels', 'slot_loop', ('int64', 'int64', 'int64', 'float64', 'int64', 'float64', 'float64', 'int64', 'int64[1C]', 'int64[1C]', 'float64[2C]', 'int64[1C]', 'int64[1C]', 'float64[1C]', 'float64[2C]', 'float64', 'float64', 'float32[3C]', 'float64[3C]', 'int64[2C]', 'bool[3C]', 'int64[2C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[1C]', 'int64[1C]', 'int64[1C]', 'int8[1C]', 'float64[1C]', 'float64[1C]', 'int64[1C]', 'int64[1C]', 'int8[1C]', 'bool[2C]', 'int64[1C]', 'int64[1C]', 'bool[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'bool[1C]', 'int64', 'int64', 'int64[1C]', 'bool[1C]', 'int64', 'int64', 'int64', 'bool', 'int64', 'int64[1C]', 'bool[1C]', 'int64', 'int64[1C]', 'int64[2C]', 'int64[2C]', 'bool[2C]', 'int64[1C]')),
    ('swarm_envs.sensing.scale_free_kernels', 'slot_keys', ('int64[2C]', 'float64[2C]', 'float64', 'int64')),
    ('swarm_envs.sensing.scale_free_kernels', 'two_hop_triangles', ('float64[2C]', 'int64[2C]', 'int64[2C]', 'float64[2C]', 'bool[2C]', 'int64[3C]', 'float64[3C]', 'int64[1C]', 'int64')),
    ('swarm_envs.sensing.scale_free_kernels', 'two_hop_propagate', ('bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'float64[1C]', 'float64[1C]', 'bool')),
    ('swarm_envs.sensing.scale_free_kernels', 'unit_mean_positions', ('float64[2C]', 'bool[2C]', 'int64[2C]', 'float64[2C]', 'float64[2C]', 'float64')),
    ('swarm_envs.sensing.ideal', '_copy_pairs_kernel', ('float64[2C]', 'int64', 'float64')),
    ('swarm_envs.tasks.metrics', '_component_stats_kernel', ('int64[2C]', 'int64', 'int64')),
    ('swarm_envs.sensing.observation', '_clip_float32_kernel', ('float32[2C]', 'float32[1C]', 'float32[1C]')),
    ('swarm_envs.sensing.range_bearing_kernels', 'firing_sums', ('float64[2C]', 'int64[1C]', 'int64', 'float64')),
    ('swarm_envs.sensing.range_bearing_kernels', 'adc_bits', ('float64[2C]', 'float64[2C]', 'float64', 'float64', 'float64')),
    ('swarm_envs.sensing.range_bearing_kernels', '_frame_words', ('float64[2C]', 'bool[2C]', 'int64[1C]', 'bool[2C]', 'float64[2C]', 'float64', 'float64', 'float64', 'int64', 'float64')),
    ('swarm_envs.sensing.range_bearing_kernels', 'pick_ids', ('bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool', 'int64', 'int64')),
    ('swarm_envs.sensing.range_bearing_kernels', 'adc_pass', ('float64[2C]', 'int64[1C]', 'float64[2C]', 'float64', 'float64', 'float64')),
    ('swarm_envs.sensing.numpy_sums', '_sum_last', ('float64[2C]',)),
    ('swarm_envs.sensing.exchange_kernels', 'decode_bits', ('uint8[2C]', 'int64', 'int64', 'int64', 'int64')),
    ('swarm_envs.sensing.exchange_kernels', 'store_deliveries', ('int64[1C]', 'int64[1C]', 'float64[1C]', 'bool[1C]', 'int64[2C]', 'float64[2C]', 'int64[1C]', 'int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[3C]', 'float64[3C]', 'int64[2C]')),
    ('swarm_envs.sensing.observation', '_nearest_slots_kernel', ('int64', 'int64[1C]', 'float64[1C]', 'int64')),
    ('swarm_envs.sensing.observation', '_range_bearing_kernel', ('int64[2C]', 'float64[1C]', 'float64[3C]', 'float64[3C]', 'float64[1C]')),
    ('swarm_envs.sensing.observation', '_pack_nearest_kernel', ('int64', 'int64[1C]', 'float64[1C]', 'float64[2C]', 'int64')),
    ('swarm_envs.ir.gain_kernels', '_gains_chunk', ('int64', 'int64', 'float64[3C]', 'float64[2C]', 'int64[1C]', 'float64[2C]', 'float64[2C]', 'float64[2C,ro]', 'float64[1C,ro]', 'float64[2C,ro]', 'float64[1C,ro]', 'int64', 'float64[1C]', 'float64', 'int64[1C]', 'float64[2C]', 'float64', 'bool', 'int64[1C]', 'int64[1C]', 'float64[3C]', 'float64[3C]')),
    ('swarm_envs.tasks.metrics', '_neighbourhood_sums_kernel', ('float64[2C]', 'int64[2C]')),
    ('swarm_envs.sensing.observation', '_clip_float32_kernel', ('float64[2C]', 'float32[1C]', 'float32[1C]')),
]

SCENARIOS = {
    ('AggregationTask', 'epuck'): ((0, 0.26), (1, 0.6), (2, 0.79), (3, 0.4), (4, 1.07), (5, 0.55), (6, 0.42), (7, 1.13), (8, 0.23), (9, 3.25), (10, 0.22), (11, 0.51), (12, 0.41), (13, 4.78), (14, 0.21), (15, 1.09), (16, 1.63), (17, 0.52), (18, 0.21), (19, 0.46), (20, 0.17), (21, 0.9), (22, 0.14), (23, 0.52), (24, 0.37), (25, 0.18), (26, 0.11), (27, 0.25), (28, 0.26), (29, 0.28), (30, 0.37), (31, 0.19)),
    ('AggregationTask', 'droplet'): ((0, 0.27), (1, 0.65), (2, 0.78), (3, 0.41), (4, 1.08), (5, 0.61), (6, 0.44), (7, 1.12), (8, 0.22), (9, 3.19), (10, 0.2), (11, 0.47), (12, 0.38), (13, 4.44), (14, 0.21), (15, 1.06), (16, 1.58), (17, 0.53), (18, 0.17), (19, 0.48), (20, 0.18), (21, 0.96), (22, 0.16), (23, 0.54), (24, 0.4), (25, 0.21), (26, 0.11), (29, 0.3), (30, 0.2), (27, 0.46), (28, 0.29), (31, 0.22)),
    ('AggregationTask', 'rone'): ((3, 0.36), (4, 1.24), (5, 0.67), (6, 0.35), (7, 1.33), (8, 0.24), (32, 3.49), (10, 0.23), (12, 0.47), (13, 4.55), (14, 0.25), (15, 1.13), (16, 1.41), (17, 0.51), (18, 0.17), (19, 0.62), (20, 0.16), (0, 0.29), (1, 0.48), (2, 0.71), (27, 0.25), (28, 0.27), (29, 0.29), (30, 0.19)),
    ('FlockingTask', 'epuck'): ((0, 0.28), (1, 0.6), (2, 0.76), (3, 0.4), (4, 1.06), (5, 0.58), (6, 0.46), (7, 1.16), (8, 0.23), (9, 3.18), (10, 0.2), (11, 0.47), (12, 0.38), (13, 4.16), (14, 0.22), (15, 1.04), (16, 1.48), (17, 0.51), (18, 0.18), (33, 0.17), (20, 0.17), (21, 0.84), (22, 0.14), (23, 0.49), (24, 0.18), (25, 0.17), (26, 0.11), (27, 0.39), (28, 0.25), (29, 0.26), (30, 0.18), (31, 0.34)),
    ('CentroidSeekingTask', 'epuck'): ((3, 0.32), (4, 1.06), (5, 0.59), (6, 0.32), (7, 1.23), (8, 0.23), (9, 3.16), (10, 0.21), (11, 0.37), (12, 0.54), (13, 4.38), (14, 0.26), (15, 1.1), (16, 1.4), (17, 0.72), (20, 0.18), (0, 0.27), (1, 0.46), (2, 0.76), (21, 0.6), (22, 0.14), (23, 0.69), (24, 0.2), (25, 0.19), (26, 0.11), (29, 0.28), (30, 0.35), (27, 0.25), (28, 0.26), (31, 0.2)),
    ('SortedFollowingTask', 'rone'): ((3, 0.34), (4, 1.12), (5, 0.64), (6, 0.33), (7, 1.28), (8, 0.22), (32, 3.38), (10, 0.21), (12, 0.43), (13, 4.69), (14, 0.26), (15, 1.16), (16, 1.43), (17, 0.51), (20, 0.18), (2, 0.76), (31, 0.49), (34, 0.15), (0, 0.28), (1, 0.63), (30, 0.19), (27, 0.25), (28, 0.25)),
    ('ParityClusteringTask', 'rone'): ((3, 0.33), (4, 1.1), (5, 0.6), (6, 0.31), (7, 1.28), (8, 0.23), (32, 3.19), (10, 0.2), (12, 0.41), (13, 4.48), (14, 0.25), (15, 1.12), (16, 1.43), (17, 0.51), (18, 0.18), (19, 0.68), (20, 0.17), (2, 0.57), (0, 0.26), (1, 0.61), (31, 0.46), (34, 0.14), (30, 0.19), (27, 0.42), (28, 0.27)),
    ('MidAngleNavigationTask', 'rone'): ((3, 0.32), (4, 1.07), (5, 0.59), (6, 0.32), (7, 1.22), (8, 0.22), (32, 3.14), (12, 0.41), (13, 4.68), (14, 0.24), (15, 0.86), (16, 1.68), (17, 0.52), (20, 0.17), (2, 0.73), (31, 0.49), (34, 0.19), (0, 0.45), (1, 0.58), (30, 0.19), (27, 0.25), (28, 0.26)),
}
