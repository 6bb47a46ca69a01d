"""The numba kernels each scenario compiles, in order of first use (:mod:`swarm_envs._compile._first_run`).

Written by ``python -m swarm_envs._compile._kernel_record``; do not edit. ``KERNELS``: (module, function,
argument types) of kernels called from Python; ``SCENARIOS``: (task class, platform) -> (index into
KERNELS, process seconds its compile took on the recording machine) in order of first use."""

NUMBA_VERSION = '0.68.1'

KERNELS = [
    ('swarm_envs.sensing.kernels', 'roll_tables', ('int64[1C]', 'int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[3C]', 'float64[3C]', 'int64[2C]', 'int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[3C]', 'float64[3C]', 'int64[2C]', 'int64')),
    ('swarm_envs.sensing.kernels', 'encode_tables', ('int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[1C]', 'int64[1C]', 'int64', 'int64', 'int64', 'int64')),
    ('swarm_envs.comm.kernels', 'build_frames', ('int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'int64[1C]', 'int64', 'int64', 'bool', 'int64', 'int64[1C]', 'int64', 'int64', 'bool[2C]')),
    ('swarm_envs.comm.kernels', '_generator_list', ('generator',)),
    ('swarm_envs.comm.kernels', '_draw_copies_nb', ('list[generator]', 'int64', 'int64', 'int64', 'float64', 'int64', 'uint32[1C]', 'float32[1C]', 'float32[1C]', 'float32', 'float32')),
    ('swarm_envs.ir.kernels', 'directed_pairs_kernel', ('int64[2C]', 'float64[2C]', 'float64[1C]', 'float64[1C]', 'float64[1C]')),
    ('swarm_envs.ir.kernels', 'neighbour_csr_kernel', ('float64[2C]', 'int64[2C]', 'float64')),
    ('swarm_envs.ir.kernels', 'occluders_kernel', ('float64[2C]', 'float64', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]')),
    ('swarm_envs.ir.kernels', 'occluder_frames_kernel', ('float64[2C]', 'float64[1C]', 'float64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]')),
    ('swarm_envs.ir.kernels', '_gains_serial', ('float64[2C]', 'float64[2C]', 'float64[2C,ro]', 'float64[1C,ro]', 'float64[2C,ro]', 'float64[1C,ro]', 'int64', 'float64[1C]', 'float64', 'int64[1C]', 'float64[2C]', 'float64', 'bool', 'int64[1C]', 'int64[1C]', 'float64[3C,ro]', 'float64[3C,ro]')),
    ('swarm_envs.ir.kernels', 'select_links_kernel', ('int64[1C]', 'int64[1C]', 'int64[1C]', 'float64[2C]', 'float64[1C]', 'float64[1C]')),
    ('swarm_envs.sensing.kernels', 'merge_readings', ('int64[1C]', 'float64[2C]', 'int64[2C]', 'int64', 'int64[1C]', 'float64[2C]', 'int64[2C]')),
    ('swarm_envs.comm.kernels', 'link_tables', ('int64', 'int64[1C]', 'int64[1C]', 'float64[3C]', 'float64', 'float64[1C]', 'float64', 'float64')),
    ('swarm_envs.comm.kernels', 'slot_loop', ('int64', 'int64', 'int64', 'float64', 'int64', 'float64', 'float64', 'int64', 'int64[1C]', 'int64[1C]', 'float64[2C]', 'int64[1C]', 'int64[1C]', 'float64[1C]', 'float64[2C]', 'float64', 'float64', 'float32[3C]', 'float64[3C]', 'int64[2C]', 'bool[3C]', 'int64[2C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[1C]', 'int64[1C]', 'int64[1C]', 'int8[1C]', 'float64[1C]', 'float64[1C]', 'int64[1C]', 'int64[1C]', 'int8[1C]', 'bool[2C]', 'int64[1C]', 'int64[1C]', 'bool[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'bool[1C]', 'int64', 'int64', 'int64[1C]', 'bool[1C]', 'int64', 'int64', 'int64', 'bool', 'int64', 'int64[1C]', 'bool[1C]', 'int64', 'int64[1C]', 'int64[2C]', 'int64[2C]', 'bool[2C]', 'int64[1C]')),
    ('swarm_envs.sensing.kernels', 'slot_keys', ('int64[2C]', 'float64[2C]', 'float64', 'int64')),
    ('swarm_envs.sensing.kernels', 'two_hop_triangles', ('float64[2C]', 'int64[2C]', 'int64[2C]', 'float64[2C]', 'bool[2C]', 'int64[3C]', 'float64[3C]', 'int64[1C]', 'int64')),
    ('swarm_envs.sensing.kernels', 'two_hop_propagate', ('bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'float64[1C]', 'float64[1C]', 'bool')),
    ('swarm_envs.sensing.kernels', 'unit_mean_positions', ('float64[2C]', 'bool[2C]', 'int64[2C]', 'float64[2C]', 'float64[2C]', 'float64')),
    ('swarm_envs.sensing.ideal', '_copy_pairs_kernel', ('float64[2C]', 'int64', 'float64')),
    ('swarm_envs.tasks.metrics', '_component_stats_kernel', ('int64[2C]', 'int64', 'int64')),
    ('swarm_envs.sensing.observation', '_clip_float32_kernel', ('float32[2C]', 'float32[1C]', 'float32[1C]')),
    ('swarm_envs.sensing.kernels', 'firing_sums', ('float64[2C]', 'int64[1C]', 'int64', 'float64')),
    ('swarm_envs.sensing.kernels', 'adc_bits', ('float64[2C]', 'float64[2C]', 'float64', 'float64', 'float64')),
    ('swarm_envs.sensing.kernels', '_frame_words', ('float64[2C]', 'bool[2C]', 'int64[1C]', 'bool[2C]', 'float64[2C]', 'float64', 'float64', 'float64', 'int64', 'float64')),
    ('swarm_envs.sensing.kernels', 'pick_ids', ('bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool', 'int64', 'int64')),
    ('swarm_envs.sensing.kernels', 'adc_pass', ('float64[2C]', 'int64[1C]', 'float64[2C]', 'float64', 'float64', 'float64')),
    ('swarm_envs.sensing.kernels', '_sum_last', ('float64[2C]',)),
    ('swarm_envs.sensing.kernels', 'decode_bits', ('uint8[2C]', 'int64', 'int64', 'int64', 'int64')),
    ('swarm_envs.sensing.kernels', 'store_deliveries', ('int64[1C]', 'int64[1C]', 'float64[1C]', 'bool[1C]', 'int64[2C]', 'float64[2C]', 'int64[1C]', 'int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[3C]', 'float64[3C]', 'int64[2C]')),
    ('swarm_envs.sensing.observation', '_nearest_slots_kernel', ('int64', 'int64[1C]', 'float64[1C]', 'int64')),
    ('swarm_envs.sensing.observation', '_range_bearing_kernel', ('int64[2C]', 'float64[1C]', 'float64[3C]', 'float64[3C]', 'float64[1C]')),
    ('swarm_envs.sensing.observation', '_pack_nearest_kernel', ('int64', 'int64[1C]', 'float64[1C]', 'float64[2C]', 'int64')),
    ('swarm_envs.ir.kernels', '_gains_serial', ('float64[2C]', 'float64[2C]', 'float64[2C,ro]', 'float64[1C,ro]', 'float64[2C,ro]', 'float64[1C,ro]', 'int64', 'float64[1C]', 'float64', 'int64[1C]', 'float64[2C]', 'float64', 'bool', 'int64[1C]', 'int64[1C]', 'float64[3C]', 'float64[3C]')),
    ('swarm_envs.tasks.metrics', '_neighbourhood_sums_kernel', ('float64[2C]', 'int64[2C]')),
    ('swarm_envs.sensing.observation', '_clip_float32_kernel', ('float64[2C]', 'float32[1C]', 'float32[1C]')),
]

SCENARIOS = {
    ('AggregationTask', 'epuck'): ((0, 0.22), (1, 0.5), (2, 0.64), (3, 0.36), (4, 0.94), (5, 0.46), (6, 0.35), (7, 0.95), (8, 0.27), (9, 3.14), (10, 0.3), (11, 0.29), (12, 0.33), (13, 3.61), (14, 0.32), (15, 0.82), (16, 1.17), (17, 0.43), (18, 0.28), (19, 0.39), (20, 0.15), (21, 0.5), (22, 0.24), (23, 0.43), (24, 0.16), (25, 0.15), (26, 0.09), (27, 0.21), (28, 0.33), (29, 0.23), (30, 0.16), (31, 0.16)),
    ('AggregationTask', 'droplet'): ((0, 0.21), (1, 0.48), (2, 0.63), (3, 0.36), (4, 0.93), (5, 0.46), (6, 0.36), (7, 0.95), (8, 0.19), (9, 3.2), (10, 0.3), (11, 0.29), (12, 0.33), (13, 3.72), (14, 0.18), (15, 0.71), (16, 1.31), (17, 0.44), (18, 0.15), (19, 0.39), (20, 0.3), (21, 0.5), (22, 0.12), (23, 0.42), (24, 0.29), (25, 0.15), (26, 0.09), (29, 0.24), (30, 0.16), (27, 0.33), (28, 0.21), (31, 0.16)),
    ('AggregationTask', 'rone'): ((3, 0.3), (4, 0.97), (5, 0.52), (6, 0.27), (7, 1.03), (8, 0.19), (32, 3.25), (10, 0.18), (12, 0.47), (13, 3.69), (14, 0.21), (15, 0.86), (16, 1.14), (17, 0.55), (18, 0.15), (19, 0.38), (20, 0.15), (0, 0.32), (1, 0.37), (2, 0.44), (27, 0.31), (28, 0.21), (31, 0.4), (30, 0.27)),
    ('FlockingTask', 'epuck'): ((0, 0.21), (1, 0.48), (2, 0.62), (3, 0.34), (4, 0.89), (5, 0.45), (6, 0.34), (7, 0.93), (8, 0.19), (9, 3.16), (10, 0.28), (11, 0.29), (12, 0.32), (13, 3.64), (14, 0.18), (15, 0.71), (16, 1.28), (17, 0.43), (18, 0.15), (33, 0.14), (20, 0.14), (21, 0.64), (22, 0.12), (23, 0.42), (24, 0.27), (25, 0.15), (26, 0.09), (27, 0.2), (28, 0.21), (29, 0.23), (30, 0.28), (31, 0.16)),
    ('CentroidSeekingTask', 'epuck'): ((3, 0.29), (4, 0.94), (5, 0.5), (6, 0.27), (7, 0.99), (8, 0.18), (9, 3.12), (10, 0.18), (11, 0.43), (12, 0.32), (13, 3.67), (14, 0.21), (15, 0.84), (16, 1.14), (17, 0.54), (20, 0.14), (0, 0.21), (1, 0.46), (2, 0.43), (21, 0.6), (22, 0.12), (23, 0.42), (24, 0.16), (25, 0.15), (26, 0.09), (29, 0.35), (30, 0.16), (27, 0.2), (28, 0.21), (31, 0.16)),
    ('SortedFollowingTask', 'rone'): ((3, 0.29), (4, 0.93), (5, 0.5), (6, 0.27), (7, 1.0), (8, 0.18), (32, 3.11), (10, 0.17), (12, 0.46), (13, 3.69), (14, 0.21), (15, 0.85), (16, 1.14), (17, 0.54), (20, 0.14), (2, 0.42), (31, 0.5), (34, 0.11), (0, 0.21), (1, 0.36), (30, 0.26), (27, 0.2), (28, 0.21)),
    ('ParityClusteringTask', 'rone'): ((3, 0.3), (4, 0.95), (5, 0.5), (6, 0.27), (7, 1.0), (8, 0.19), (32, 3.17), (10, 0.18), (12, 0.47), (13, 3.7), (14, 0.21), (15, 0.85), (16, 1.16), (17, 0.44), (18, 0.28), (19, 0.39), (20, 0.15), (2, 0.54), (0, 0.21), (1, 0.36), (31, 0.53), (34, 0.11), (30, 0.15), (27, 0.2), (28, 0.21)),
    ('MidAngleNavigationTask', 'rone'): ((3, 0.3), (4, 0.95), (5, 0.51), (6, 0.27), (7, 1.0), (8, 0.19), (32, 3.15), (12, 0.35), (13, 3.81), (14, 0.21), (15, 0.86), (16, 1.15), (17, 0.44), (20, 0.14), (2, 0.57), (31, 0.4), (34, 0.22), (0, 0.21), (1, 0.36), (30, 0.16), (27, 0.31), (28, 0.21)),
}
