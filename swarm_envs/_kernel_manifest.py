"""The numba kernels each scenario compiles, in order of first use (:mod:`swarm_envs._first_run`).

Written by ``python -m swarm_envs._kernel_record``; do not edit. ``KERNELS``: (module, function,
argument types) of kernels called from Python; ``SCENARIOS``: (task class, platform) -> (index into
KERNELS, process seconds its compile took on the recording machine) in order of first use."""

NUMBA_VERSION = '0.68.1'

KERNELS = [
    ('swarm_envs.sensing.kernels', 'roll_tables', ('int64[1C]', 'int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[3C]', 'float64[3C]', 'int64[2C]', 'int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[3C]', 'float64[3C]', 'int64[2C]', 'int64')),
    ('swarm_envs.sensing.kernels', 'encode_tables', ('int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[1C]', 'int64[1C]', 'int64', 'int64', 'int64', 'int64')),
    ('swarm_envs.comm.kernels', 'build_frames', ('int64[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'int64[1C]', 'int64', 'int64', 'bool', 'int64', 'int64[1C]', 'int64', 'int64', 'bool[2C]')),
    ('swarm_envs.comm.kernels', '_draw_copies_nb', ('list[generator]', 'int64', 'int64', 'int64', 'float64', 'float64', 'int64', 'uint32[1C]', 'float32[1C]', 'float32[1C]', 'float32', 'float32')),
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
    ('swarm_envs.metrics', '_component_stats_kernel', ('int64[2C]', 'int64', 'int64')),
    ('swarm_envs.observation', '_clip_float32_kernel', ('float32[2C]', 'float32[1C]', 'float32[1C]')),
    ('swarm_envs.sensing.kernels', 'firing_sums', ('float64[2C]', 'int64[1C]', 'int64', 'float64')),
    ('swarm_envs.sensing.kernels', 'adc_bits', ('float64[2C]', 'float64[2C]', 'float64', 'float64', 'float64')),
    ('swarm_envs.sensing.kernels', '_frame_words', ('float64[2C]', 'bool[2C]', 'int64[1C]', 'bool[2C]', 'float64[2C]', 'float64', 'float64', 'float64', 'int64', 'float64')),
    ('swarm_envs.sensing.kernels', 'pick_ids', ('bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool', 'int64', 'int64')),
    ('swarm_envs.sensing.kernels', 'adc_pass', ('float64[2C]', 'int64[1C]', 'float64[2C]', 'float64', 'float64', 'float64')),
    ('swarm_envs.sensing.kernels', '_sum_last', ('float64[2C]',)),
    ('swarm_envs.sensing.kernels', 'decode_bits', ('uint8[2C]', 'int64', 'int64', 'int64', 'int64')),
    ('swarm_envs.sensing.kernels', 'store_deliveries', ('int64[1C]', 'int64[1C]', 'float64[1C]', 'bool[1C]', 'int64[2C]', 'float64[2C]', 'int64[1C]', 'int64[2C]', 'float64[2C]', 'int64[2C]', 'int64[3C]', 'float64[3C]', 'int64[2C]')),
    ('swarm_envs.observation', '_nearest_slots_kernel', ('int64', 'int64[1C]', 'float64[1C]', 'int64')),
    ('swarm_envs.observation', '_range_bearing_kernel', ('int64[2C]', 'float64[1C]', 'float64[3C]', 'float64[3C]', 'float64[1C]')),
    ('swarm_envs.observation', '_pack_nearest_kernel', ('int64', 'int64[1C]', 'float64[1C]', 'float64[2C]', 'int64')),
    ('swarm_envs.ir.kernels', '_gains_serial', ('float64[2C]', 'float64[2C]', 'float64[2C,ro]', 'float64[1C,ro]', 'float64[2C,ro]', 'float64[1C,ro]', 'int64', 'float64[1C]', 'float64', 'int64[1C]', 'float64[2C]', 'float64', 'bool', 'int64[1C]', 'int64[1C]', 'float64[3C]', 'float64[3C]')),
    ('swarm_envs.metrics', '_neighbourhood_sums_kernel', ('float64[2C]', 'int64[2C]')),
    ('swarm_envs.observation', '_clip_float32_kernel', ('float64[2C]', 'float32[1C]', 'float32[1C]')),
]

SCENARIOS = {
    ('AggregationTask', 'epuck'): ((0, 0.35), (1, 0.75), (2, 1.13), (3, 2.42), (4, 0.71), (5, 0.32), (6, 1.31), (7, 0.22), (8, 4.34), (9, 0.23), (10, 0.71), (11, 0.44), (12, 4.62), (13, 0.26), (14, 1.34), (15, 1.47), (16, 0.73), (17, 0.21), (18, 0.86), (19, 0.29), (20, 0.9), (21, 0.19), (22, 0.81), (23, 0.24), (24, 0.22), (25, 0.16), (26, 0.47), (27, 0.32), (28, 0.67), (29, 0.24), (30, 0.22)),
    ('AggregationTask', 'droplet'): ((0, 0.42), (1, 0.91), (2, 1.44), (3, 3.89), (4, 0.97), (5, 0.58), (6, 1.99), (7, 0.24), (8, 6.17), (9, 0.24), (10, 0.9), (11, 0.45), (12, 5.97), (13, 0.28), (14, 1.61), (15, 1.8), (16, 0.83), (17, 0.3), (18, 0.95), (19, 0.29), (20, 0.68), (21, 0.2), (22, 1.04), (23, 0.29), (24, 0.21), (25, 0.13), (28, 0.49), (29, 0.29), (26, 0.62), (27, 0.33), (30, 0.23)),
    ('AggregationTask', 'rone'): ((3, 2.71), (4, 0.8), (5, 0.36), (6, 1.5), (7, 0.24), (31, 4.67), (9, 0.22), (11, 0.57), (12, 5.49), (13, 0.58), (14, 1.46), (15, 1.53), (16, 0.6), (17, 0.2), (18, 0.43), (19, 0.26), (0, 0.55), (1, 0.57), (2, 0.64), (26, 0.61), (27, 0.29), (30, 0.6), (29, 0.26)),
    ('FlockingTask', 'epuck'): ((0, 0.3), (1, 0.83), (2, 1.11), (3, 2.74), (4, 0.77), (5, 0.35), (6, 1.43), (7, 0.28), (8, 4.81), (9, 0.23), (10, 0.78), (11, 0.49), (12, 5.72), (13, 0.29), (14, 1.53), (15, 1.37), (16, 0.59), (17, 0.19), (32, 0.47), (19, 0.19), (20, 0.71), (21, 0.16), (22, 0.71), (23, 0.2), (24, 0.18), (25, 0.12), (26, 0.37), (27, 0.29), (28, 0.35), (29, 0.5), (30, 0.19)),
    ('CentroidSeekingTask', 'epuck'): ((3, 3.06), (4, 0.76), (5, 0.34), (6, 1.44), (7, 0.23), (8, 4.71), (9, 0.23), (10, 0.61), (11, 0.56), (12, 4.87), (13, 0.27), (14, 1.41), (15, 1.38), (16, 0.6), (19, 0.2), (0, 0.28), (1, 0.86), (2, 0.68), (20, 0.89), (21, 0.22), (22, 0.68), (23, 0.21), (24, 0.17), (25, 0.14), (28, 0.65), (29, 0.25), (26, 0.34), (27, 0.27), (30, 0.19)),
    ('SortedFollowingTask', 'rone'): ((3, 2.62), (4, 0.73), (5, 0.35), (6, 1.45), (7, 0.24), (31, 4.72), (9, 0.23), (11, 0.53), (12, 5.14), (13, 0.57), (14, 1.43), (15, 1.56), (16, 0.59), (19, 0.2), (2, 0.61), (30, 0.87), (33, 0.15), (0, 0.36), (1, 0.76), (29, 0.24), (26, 0.31), (27, 0.27)),
    ('ParityClusteringTask', 'rone'): ((3, 2.96), (4, 0.75), (5, 0.37), (6, 1.45), (7, 0.3), (31, 4.88), (9, 0.25), (11, 0.53), (12, 6.18), (13, 0.64), (14, 1.64), (15, 1.67), (16, 0.63), (17, 0.27), (18, 0.58), (19, 0.25), (2, 0.93), (0, 0.3), (1, 0.58), (30, 0.88), (33, 0.16), (29, 0.26), (26, 0.33), (27, 0.49)),
    ('MidAngleNavigationTask', 'rone'): ((3, 3.04), (4, 0.77), (5, 0.41), (6, 1.47), (7, 0.26), (31, 5.36), (11, 0.56), (12, 5.36), (13, 0.36), (14, 1.68), (15, 1.53), (16, 0.85), (19, 0.2), (2, 0.64), (30, 0.97), (33, 0.21), (0, 0.38), (1, 0.74), (29, 0.24), (26, 0.52), (27, 0.32)),
}
