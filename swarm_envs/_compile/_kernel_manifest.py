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
    ('swarm_envs.ir.gain_kernels', '_gains_serial', ('float64[2C]', 'float64[2C]', 'float64[2C,ro]', 'float64[1C,ro]', 'float64[2C,ro]', 'float64[1C,ro]', 'int64', 'float64[1C]', 'float64', 'int64[1C]', 'float64[2C]', 'float64', 'bool', 'int64[1C]', 'int64[1C]', 'float64[3C,ro]', 'float64[3C,ro]')),
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
    ('swarm_envs.ir.gain_kernels', '_gains_serial', ('float64[2C]', 'float64[2C]', 'float64[2C,ro]', 'float64[1C,ro]', 'float64[2C,ro]', 'float64[1C,ro]', 'int64', 'float64[1C]', 'float64', 'int64[1C]', 'float64[2C]', 'float64', 'bool', 'int64[1C]', 'int64[1C]', 'float64[3C]', 'float64[3C]')),
    ('swarm_envs.tasks.metrics', '_neighbourhood_sums_kernel', ('float64[2C]', 'int64[2C]')),
    ('swarm_envs.sensing.observation', '_clip_float32_kernel', ('float64[2C]', 'float32[1C]', 'float32[1C]')),
]

SCENARIOS = {
    ('AggregationTask', 'epuck'): ((0, 0.27), (1, 0.61), (2, 0.76), (3, 0.44), (4, 1.14), (5, 0.59), (6, 0.45), (7, 1.24), (8, 0.27), (9, 4.41), (10, 0.38), (11, 0.38), (12, 0.42), (13, 4.85), (14, 0.25), (15, 0.99), (16, 1.94), (17, 0.58), (18, 0.19), (19, 0.76), (20, 0.2), (21, 0.67), (22, 0.16), (23, 0.83), (24, 0.21), (25, 0.19), (26, 0.12), (27, 0.28), (28, 0.29), (29, 0.52), (30, 0.2), (31, 0.22)),
    ('AggregationTask', 'droplet'): ((0, 0.3), (1, 0.69), (2, 0.88), (3, 0.54), (4, 1.29), (5, 0.75), (6, 0.55), (7, 1.47), (8, 0.3), (9, 4.89), (10, 0.42), (11, 0.4), (12, 0.44), (13, 5.36), (14, 0.26), (15, 1.18), (16, 2.01), (17, 0.65), (18, 0.21), (19, 0.79), (20, 0.21), (21, 0.78), (22, 0.17), (23, 0.87), (24, 0.22), (25, 0.22), (26, 0.13), (29, 0.39), (30, 0.26), (27, 0.54), (28, 0.31), (31, 0.23)),
    ('AggregationTask', 'rone'): ((3, 0.47), (4, 1.69), (5, 0.87), (6, 0.4), (7, 1.52), (8, 0.27), (32, 4.97), (10, 0.26), (12, 0.72), (13, 5.63), (14, 0.31), (15, 1.45), (16, 1.78), (17, 0.78), (18, 0.19), (19, 0.5), (20, 0.19), (0, 0.49), (1, 0.49), (2, 0.6), (27, 0.45), (28, 0.28), (29, 0.3), (30, 0.21)),
    ('FlockingTask', 'epuck'): ((0, 0.32), (1, 0.71), (2, 0.92), (3, 0.48), (4, 1.29), (5, 0.67), (6, 0.55), (7, 1.38), (8, 0.27), (9, 4.91), (10, 0.43), (11, 0.41), (12, 0.47), (13, 5.26), (14, 0.26), (15, 1.04), (16, 1.95), (17, 0.62), (18, 0.21), (33, 0.19), (20, 0.45), (21, 0.69), (22, 0.16), (23, 0.8), (24, 0.22), (25, 0.19), (26, 0.12), (27, 0.28), (28, 0.3), (29, 0.52), (30, 0.2), (31, 0.21)),
    ('CentroidSeekingTask', 'epuck'): ((3, 0.39), (4, 1.37), (5, 0.75), (6, 0.41), (7, 1.61), (8, 0.27), (9, 4.27), (10, 0.21), (11, 0.6), (12, 0.42), (13, 4.75), (14, 0.28), (15, 1.23), (16, 1.71), (17, 0.57), (20, 0.18), (0, 0.29), (1, 0.79), (2, 0.66), (21, 0.73), (22, 0.39), (23, 0.65), (24, 0.23), (25, 0.21), (26, 0.13), (29, 0.54), (30, 0.22), (27, 0.3), (28, 0.3), (31, 0.22)),
    ('SortedFollowingTask', 'rone'): ((3, 0.39), (4, 1.29), (5, 0.73), (6, 0.38), (7, 1.49), (8, 0.26), (32, 4.7), (10, 0.22), (12, 0.67), (13, 4.66), (14, 0.26), (15, 1.12), (16, 1.46), (17, 0.69), (20, 0.2), (2, 0.6), (31, 0.66), (34, 0.14), (0, 0.29), (1, 0.53), (30, 0.41), (27, 0.26), (28, 0.27)),
    ('ParityClusteringTask', 'rone'): ((3, 0.34), (4, 1.18), (5, 0.65), (6, 0.33), (7, 1.25), (8, 0.23), (32, 4.0), (10, 0.24), (12, 0.73), (13, 5.38), (14, 0.29), (15, 1.29), (16, 1.69), (17, 0.77), (18, 0.18), (19, 0.46), (20, 0.19), (2, 0.73), (0, 0.26), (1, 0.44), (31, 0.61), (34, 0.13), (30, 0.18), (27, 0.23), (28, 0.41)),
    ('MidAngleNavigationTask', 'rone'): ((3, 0.34), (4, 1.14), (5, 0.64), (6, 0.32), (7, 1.28), (8, 0.23), (32, 4.04), (12, 0.59), (13, 4.57), (14, 0.28), (15, 1.29), (16, 1.62), (17, 0.81), (20, 0.2), (2, 0.63), (31, 0.54), (34, 0.37), (0, 0.29), (1, 0.5), (30, 0.21), (27, 0.46), (28, 0.28)),
}
