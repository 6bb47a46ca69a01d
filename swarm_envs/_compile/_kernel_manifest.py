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
    ('swarm_envs.comm.kernels', 'slot_loop', ('int64', 'int64', 'int64', 'float64', 'int64', 'float64', 'float64', 'int64', 'int64[1C]', 'int64[1C]', 'float64[2C]', 'int64[1C]', 'int64[1C]', 'float64[1C]', 'float64[2C]', 'float64', 'float64', 'float32[3C]', 'float64[3C]', 'int64[2C]', 'bool[3C]', 'int64[2C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[1C]', 'int64[1C]', 'int8[1C]', 'float64[1C]', 'float64[1C]', 'int64[1C]', 'int64[1C]', 'int8[1C]', 'bool[2C]', 'int64[1C]', 'int64[1C]', 'bool[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'bool[1C]', 'int64', 'int64', 'int64[1C]', 'bool[1C]', 'int64', 'int64', 'int64', 'bool', 'int64', 'int64[1C]', 'bool[1C]', 'int64', 'int64[1C]', 'int64[2C]', 'int64[2C]', 'bool[2C]', 'int64[1C]', 'int64', 'int64')),
    ('swarm_envs.sensing.scale_free_kernels', 'slot_keys', ('int64[2C]', 'float64[2C]', 'float64', 'int64')),
    ('swarm_envs.sensing.scale_free_kernels', 'two_hop_triangles', ('float64[2C]', 'int64[2C]', 'int64[2C]', 'float64[2C]', 'bool[2C]', 'int64[3C]', 'float64[3C]', 'int64[1C]', 'int64')),
    ('swarm_envs.sensing.scale_free_kernels', 'two_hop_propagate', ('bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'float64[1C]', 'float64[1C]', 'bool')),
    ('swarm_envs.sensing.scale_free_kernels', 'unit_mean_positions', ('float64[2C]', 'bool[2C]', 'int64[2C]', 'float64[2C]', 'float64[2C]', 'float64')),
    ('swarm_envs.sensing.ideal', '_copy_pairs_kernel', ('float64[2C]', 'int64', 'float64')),
    ('swarm_envs.tasks.metrics', '_component_stats_kernel', ('int64[2C]', 'int64', 'int64')),
    ('swarm_envs.sensing.observation', '_clip_float32_kernel', ('float32[2C]', 'float32[1C]', 'float32[1C]')),
    ('swarm_envs.sim.substep_kernel', 'motor_forces', ('float64[2C]', 'float64[1C]', 'float64[1C]', 'float64', 'float64', 'float64', 'float64', 'float64')),
    ('swarm_envs.sim.substep_kernel', 'contact_rows', ('uint64[2C]',)),
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
    ('AggregationTask', 'epuck'): ((0, 0.3), (1, 0.65), (2, 0.85), (3, 0.46), (4, 1.21), (5, 0.63), (6, 0.39), (7, 1.4), (8, 0.26), (9, 3.46), (10, 0.38), (11, 0.4), (12, 0.42), (13, 5.18), (14, 0.24), (15, 1.17), (16, 1.79), (17, 0.6), (18, 0.2), (19, 0.5), (20, 0.19), (21, 0.36), (22, 0.58), (23, 0.7), (24, 0.16), (25, 0.76), (26, 0.27), (27, 0.26), (28, 0.11), (29, 0.27), (30, 0.5), (31, 0.32), (32, 0.22), (33, 0.22)),
    ('AggregationTask', 'droplet'): ((0, 0.29), (1, 0.65), (2, 0.85), (3, 0.39), (4, 1.2), (5, 0.65), (6, 0.39), (7, 1.4), (8, 0.26), (9, 3.48), (10, 0.38), (11, 0.39), (12, 0.43), (13, 5.44), (14, 0.29), (15, 1.19), (16, 1.69), (17, 0.59), (18, 0.2), (19, 0.49), (20, 0.19), (21, 0.38), (22, 0.59), (23, 0.69), (24, 0.16), (25, 0.74), (26, 0.22), (27, 0.2), (28, 0.11), (31, 0.31), (32, 0.38), (29, 0.27), (30, 0.37), (33, 0.28)),
    ('AggregationTask', 'rone'): ((3, 0.4), (4, 1.28), (5, 0.71), (6, 0.39), (7, 1.4), (8, 0.26), (34, 3.56), (10, 0.26), (12, 0.61), (13, 5.73), (14, 0.29), (15, 1.2), (16, 1.63), (17, 0.61), (18, 0.36), (19, 0.49), (20, 0.2), (21, 0.16), (22, 0.69), (0, 0.28), (1, 0.48), (2, 0.73), (29, 0.27), (30, 0.29), (31, 0.46), (32, 0.21)),
    ('FlockingTask', 'epuck'): ((0, 0.29), (1, 0.64), (2, 0.86), (3, 0.39), (4, 1.18), (5, 0.61), (6, 0.36), (7, 1.33), (8, 0.25), (9, 3.49), (10, 0.39), (11, 0.41), (12, 0.44), (13, 5.34), (14, 0.24), (15, 1.19), (16, 1.72), (17, 0.58), (18, 0.2), (35, 0.2), (20, 0.19), (21, 0.16), (22, 0.56), (23, 0.87), (24, 0.16), (25, 0.58), (26, 0.36), (27, 0.2), (28, 0.11), (29, 0.27), (30, 0.28), (31, 0.31), (32, 0.38), (33, 0.22)),
    ('CentroidSeekingTask', 'epuck'): ((3, 0.39), (4, 1.27), (5, 0.67), (6, 0.36), (7, 1.35), (8, 0.25), (9, 3.55), (10, 0.24), (11, 0.57), (12, 0.43), (13, 5.43), (14, 0.28), (15, 1.14), (16, 1.7), (17, 0.6), (20, 0.2), (21, 0.16), (22, 0.57), (0, 0.48), (1, 0.48), (2, 0.59), (23, 0.83), (24, 0.16), (25, 0.57), (26, 0.21), (27, 0.36), (28, 0.11), (31, 0.31), (32, 0.21), (29, 0.43), (30, 0.29), (33, 0.21)),
    ('SortedFollowingTask', 'rone'): ((3, 0.39), (4, 1.26), (5, 0.68), (6, 0.36), (7, 1.33), (8, 0.25), (34, 3.34), (10, 0.24), (12, 0.6), (13, 5.33), (14, 0.28), (15, 1.14), (16, 1.53), (17, 0.57), (20, 0.33), (21, 0.16), (22, 0.56), (2, 0.58), (33, 0.65), (36, 0.15), (0, 0.42), (1, 0.48), (32, 0.21), (29, 0.26), (30, 0.43)),
    ('ParityClusteringTask', 'rone'): ((3, 0.38), (4, 1.23), (5, 0.67), (6, 0.36), (7, 1.35), (8, 0.25), (34, 3.41), (10, 0.25), (12, 0.63), (13, 5.61), (14, 0.28), (15, 1.17), (16, 1.57), (17, 0.59), (18, 0.35), (19, 0.49), (20, 0.2), (21, 0.16), (22, 0.75), (2, 0.65), (0, 0.29), (1, 0.67), (33, 0.54), (36, 0.16), (32, 0.37), (29, 0.27), (30, 0.29)),
    ('MidAngleNavigationTask', 'rone'): ((3, 0.39), (4, 1.27), (5, 0.67), (6, 0.36), (7, 1.32), (8, 0.25), (34, 3.39), (12, 0.59), (13, 5.3), (14, 0.28), (15, 1.13), (16, 1.53), (17, 0.57), (20, 0.19), (21, 0.16), (22, 0.71), (2, 0.58), (33, 0.53), (36, 0.15), (0, 0.29), (1, 0.48), (32, 0.35), (29, 0.26), (30, 0.29)),
}
