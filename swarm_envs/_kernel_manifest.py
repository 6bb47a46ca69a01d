"""The numba kernels each scenario compiles, in order of first use (:mod:`swarm_envs._first_run`).

Written by ``python -m swarm_envs._kernel_record``; do not edit. ``KERNELS``: (module, function,
argument types) of kernels called from Python; ``SCENARIOS``: (task class, platform) -> (index into
KERNELS, process seconds its compile took on the recording machine) in order of first use."""

NUMBA_VERSION = '0.68.1'

KERNELS = [
    ('swarm_envs.sensing.kernels', 'expire_tables', ('int64[1C]', 'int64', 'int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[3C]', 'float64[3C]', 'int64[2C]', 'int64')),
    ('swarm_envs.sensing.kernels', 'encode_tables', ('int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[1C]', 'int64[1C]', 'int64', 'int64', 'int64', 'int64')),
    ('swarm_envs.comm.kernels', 'build_frames', ('int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'int64[1C]', 'int64', 'int64', 'bool', 'int64', 'int64[1C]', 'int64', 'int64', 'bool[2C]')),
    ('swarm_envs.comm.kernels', '_draw_copies_nb', ('list[generator]', 'int64', 'int64', 'int64', 'float64', 'float64', 'int64', 'uint32[1C]', 'float32[1C]', 'float32[1C]', 'float32', 'float32')),
    ('swarm_envs.ir.kernels', 'directed_pairs_kernel', ('int64[2C]', 'float64[2C]', 'float64[1C]', 'float64[1C]', 'float64[1C]')),
    ('swarm_envs.ir.kernels', 'neighbour_csr_kernel', ('float64[2C]', 'int64[2C]', 'float64')),
    ('swarm_envs.ir.kernels', 'occluders_kernel', ('float64[2C]', 'float64', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]')),
    ('swarm_envs.ir.kernels', 'occluder_frames_kernel', ('float64[2C]', 'float64[1C]', 'float64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]')),
    ('swarm_envs.ir.kernels', 'gains_kernel', ('float64[2C]', 'float64[2C]', 'float64[2C,ro]', 'float64[1C,ro]', 'float64[2C,ro]', 'float64[1C,ro]', 'int64', 'float64[1C]', 'float64', 'int64[1C]', 'float64[2C]', 'float64', 'bool')),
    ('swarm_envs.ir.kernels', 'select_links_kernel', ('int64[1C]', 'int64[1C]', 'int64[1C]', 'float64[2C]', 'float64[1C]', 'float64[1C]')),
    ('swarm_envs.sensing.kernels', 'priority_independent_set_sorted', ('float64[1C]', 'int64[1C]', 'int64[1C]')),
    ('swarm_envs.sensing.kernels', 'firing_sums', ('float64[2C]', 'int64[1C]', 'int64', 'float64')),
    ('swarm_envs.sensing.kernels', 'adc_bits', ('float64[2C]', 'float64[2C]', 'float64', 'float64', 'float64')),
    ('swarm_envs.sensing.kernels', '_frame_words', ('float64[2C]', 'bool[2C]', 'int64[1C]', 'bool[2C]', 'float64[2C]', 'float64', 'float64', 'float64', 'int64', 'float64')),
    ('swarm_envs.sensing.kernels', 'pick_ids', ('bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool', 'int64', 'int64')),
    ('swarm_envs.sensing.kernels', 'adc_pass', ('float64[2C]', 'int64[1C]', 'float64[2C]', 'float64', 'float64', 'float64')),
    ('swarm_envs.sensing.kernels', '_sum_last', ('float64[2C]',)),
    ('swarm_envs.sensing.kernels', 'merge_readings', ('int64[1C]', 'float64[2C]', 'int64[2C]', 'int64', 'int64[1C]', 'float64[2C]', 'int64[2C]')),
    ('swarm_envs.comm.kernels', 'link_tables', ('int64', 'int64[1C]', 'int64[1C]', 'float64[3C]', 'float64', 'float64[1C]', 'float64', 'float64')),
    ('swarm_envs.comm.kernels', 'slot_loop', ('int64', 'int64', 'int64', 'float64', 'int64', 'float64', 'float64', 'int64', 'int64[1C]', 'int64[1C]', 'float64[2C]', 'int64[1C]', 'int64[1C]', 'float64[1C]', 'float64[2C]', 'float64', 'float64', 'float32[3C]', 'float64[3C]', 'int64[2C]', 'bool[3C]', 'int64[2C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[1C]', 'int64[1C]', 'int64[1C]', 'int8[1C]', 'float64[1C]', 'float64[1C]', 'int64[1C]', 'int64[1C]', 'int8[1C]', 'bool[2C]', 'int64[1C]', 'int64[1C]', 'bool[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'bool[1C]', 'int64', 'int64', 'int64[1C]', 'bool[1C]', 'int64', 'int64', 'int64', 'bool', 'int64', 'int64[1C]', 'bool[1C]', 'int64', 'int64[1C]', 'int64[2C]', 'int64[2C]', 'bool[2C]')),
    ('swarm_envs.sensing.kernels', 'slot_keys', ('int64[2C]', 'float64[2C]', 'float64', 'int64')),
    ('swarm_envs.sensing.kernels', 'two_hop_triangles', ('float64[2C]', 'int64[2C]', 'int64[2C]', 'float64[2C]', 'bool[2C]', 'int64[3C]', 'float64[3C]', 'int64[1C]', 'int64')),
    ('swarm_envs.sensing.kernels', 'two_hop_propagate', ('bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'float64[1C]', 'float64[1C]', 'bool')),
    ('swarm_envs.sensing.kernels', 'unit_mean_positions', ('float64[2C]', 'bool[2C]', 'int64[2C]', 'float64[2C]', 'float64[2C]', 'float64')),
    ('swarm_envs.sensing.ideal', '_copy_pairs_kernel', ('float64[2C]', 'int64', 'float64')),
    ('swarm_envs.metrics', '_component_stats_kernel', ('int64[2C]', 'int64', 'int64')),
    ('swarm_envs.observation', '_nearest_slots_kernel', ('int64', 'int64[1C]', 'float64[1C]', 'int64')),
    ('swarm_envs.observation', '_range_bearing_kernel', ('int64[2C]', 'float64[1C]', 'float64[3C]', 'float64[3C]', 'float64[1C]')),
    ('swarm_envs.observation', '_clip_float32_kernel', ('float32[2C]', 'float32[1C]', 'float32[1C]')),
    ('swarm_envs.sensing.kernels', 'decode_bits', ('uint8[2C]', 'int64', 'int64', 'int64', 'int64')),
    ('swarm_envs.sensing.kernels', 'store_deliveries', ('int64[1C]', 'int64[1C]', 'float64[1C]', 'bool[1C]', 'int64[2C]', 'float64[2C]', 'int64[1C]', 'int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[3C]', 'float64[3C]', 'int64[2C]')),
    ('swarm_envs.observation', '_pack_nearest_kernel', ('int64', 'int64[1C]', 'float64[1C]', 'float64[2C]', 'int64')),
    ('swarm_envs.metrics', '_neighbourhood_sums_kernel', ('float64[2C]', 'int64[2C]')),
    ('swarm_envs.observation', '_clip_float32_kernel', ('float64[2C]', 'float32[1C]', 'float32[1C]')),
]

SCENARIOS = {
    ('AggregationTask', 'epuck'): ((0, 0.21), (1, 0.7), (2, 0.91), (3, 2.37), (4, 0.68), (5, 0.31), (6, 1.11), (7, 0.35), (8, 3.47), (9, 0.23), (10, 1.36), (11, 0.91), (12, 0.19), (13, 0.74), (14, 0.21), (15, 0.18), (16, 0.12), (17, 0.42), (18, 0.57), (19, 4.24), (20, 0.22), (21, 1.3), (22, 1.37), (23, 0.42), (24, 0.42), (25, 0.27), (26, 0.38), (27, 0.22), (28, 0.18), (29, 0.3), (30, 0.49), (31, 0.18)),
    ('AggregationTask', 'droplet'): ((0, 0.22), (1, 0.72), (2, 0.97), (3, 2.44), (4, 0.69), (5, 0.33), (6, 1.17), (7, 0.35), (8, 3.54), (9, 0.21), (10, 1.3), (11, 0.86), (12, 0.18), (13, 0.66), (14, 0.19), (15, 0.17), (16, 0.11), (17, 0.37), (18, 0.54), (19, 4.2), (20, 0.22), (21, 1.3), (22, 1.34), (23, 0.42), (24, 0.4), (25, 0.26), (26, 0.37), (27, 0.22), (28, 0.18), (29, 0.3), (30, 0.49), (31, 0.19)),
    ('AggregationTask', 'rone'): ((0, 0.22), (3, 2.73), (4, 0.72), (5, 0.33), (6, 1.19), (7, 0.37), (8, 3.56), (9, 0.21), (18, 0.49), (19, 4.92), (20, 0.69), (21, 1.4), (22, 1.55), (23, 0.6), (24, 0.19), (25, 0.41), (28, 0.19), (1, 0.83), (2, 0.59), (29, 0.38), (30, 0.27), (31, 0.8), (27, 0.23)),
    ('FlockingTask', 'epuck'): ((0, 0.25), (1, 0.72), (2, 0.92), (3, 2.55), (4, 0.71), (5, 0.33), (6, 1.18), (7, 0.36), (8, 3.51), (9, 0.22), (10, 1.37), (11, 0.89), (12, 0.19), (13, 0.72), (14, 0.21), (15, 0.18), (16, 0.12), (17, 0.41), (18, 0.6), (19, 4.52), (20, 0.22), (21, 1.29), (22, 1.34), (23, 0.4), (24, 0.4), (32, 0.23), (26, 0.4), (27, 0.24), (28, 0.19), (29, 0.29), (30, 0.45), (31, 0.19)),
    ('CentroidSeekingTask', 'epuck'): ((0, 0.22), (3, 2.64), (4, 0.68), (5, 0.36), (6, 1.16), (7, 0.34), (8, 3.45), (9, 0.21), (10, 1.28), (11, 0.85), (12, 0.32), (13, 0.48), (14, 0.19), (15, 0.17), (16, 0.13), (17, 0.52), (18, 0.4), (19, 4.61), (20, 0.23), (21, 1.07), (22, 1.7), (23, 0.4), (26, 0.38), (27, 0.23), (28, 0.19), (1, 0.54), (2, 0.84), (29, 0.28), (30, 0.27), (31, 0.18)),
    ('SortedFollowingTask', 'rone'): ((0, 0.21), (3, 2.58), (4, 0.69), (5, 0.32), (6, 1.14), (7, 0.35), (8, 3.67), (9, 0.22), (18, 0.47), (19, 4.61), (20, 0.54), (21, 1.23), (22, 1.76), (23, 0.61), (28, 0.18), (2, 0.56), (26, 0.37), (27, 0.5), (31, 0.2), (33, 0.14), (1, 0.54), (29, 0.3), (30, 0.5)),
    ('ParityClusteringTask', 'rone'): ((0, 0.22), (3, 2.77), (4, 0.79), (5, 0.37), (6, 1.28), (7, 0.38), (8, 3.94), (9, 0.23), (18, 0.51), (19, 4.97), (20, 0.65), (21, 1.59), (22, 1.47), (23, 0.68), (24, 0.2), (25, 0.43), (28, 0.2), (2, 1.01), (1, 0.63), (26, 0.38), (27, 0.4), (31, 0.19), (33, 0.15), (29, 0.32), (30, 0.29)),
    ('MidAngleNavigationTask', 'rone'): ((0, 0.22), (3, 2.77), (4, 0.76), (5, 0.35), (6, 1.19), (7, 0.37), (8, 3.72), (18, 0.48), (19, 4.6), (20, 0.33), (21, 1.45), (22, 1.35), (23, 0.79), (28, 0.19), (2, 0.57), (26, 0.37), (27, 0.22), (31, 0.43), (33, 0.14), (1, 0.52), (29, 0.29), (30, 0.27)),
}
