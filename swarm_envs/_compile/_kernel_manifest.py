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
    ('swarm_envs.comm.kernels', 'slot_loop', ('int64', 'int64', 'int64', 'float64', 'int64', 'float64', 'float64', 'int64', 'int64[1C]', 'int64[1C]', 'float64[2C]', 'int64[1C]', 'int64[1C]', 'float64[1C]', 'float64[2C]', 'float64', 'float64', 'float32[3C]', 'float64[3C]', 'int64[2C]', 'bool[3C]', 'int64[2C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[1C]', 'int64[1C]', 'int8[1C]', 'float64[1C]', 'float64[1C]', 'int64[1C]', 'int64[1C]', 'int8[1C]', 'bool[2C]', 'int64[1C]', 'int64[1C]', 'bool[1C]', 'int64[1C]', 'int64[1C]', 'int64[1C]', 'bool[2C]', 'bool[1C]', 'int64', 'int64', 'int64[1C]', 'bool[1C]', 'int64', 'int64', 'int64', 'bool', 'int64', 'int64[1C]', 'bool[1C]', 'int64', 'int64[1C]', 'int64[2C]', 'int64[2C]', 'bool[2C]', 'int64[1C]', 'int64', 'int64', 'bool')),
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
    ('AggregationTask', 'epuck'): ((0, 0.38), (1, 0.73), (2, 1.12), (3, 0.53), (4, 1.36), (5, 0.91), (6, 0.59), (7, 1.7), (8, 0.33), (9, 4.24), (10, 0.37), (11, 0.43), (12, 0.48), (13, 6.26), (14, 0.26), (15, 1.33), (16, 2.19), (17, 0.96), (18, 0.32), (19, 0.8), (20, 0.26), (21, 0.18), (22, 0.81), (23, 0.8), (24, 0.19), (25, 0.83), (26, 0.25), (27, 0.24), (28, 0.15), (29, 0.37), (30, 0.38), (31, 0.59), (32, 0.23), (33, 0.26)),
    ('AggregationTask', 'droplet'): ((0, 0.37), (1, 0.75), (2, 1.02), (3, 0.57), (4, 1.5), (5, 0.86), (6, 0.49), (7, 2.03), (8, 0.33), (9, 4.83), (10, 0.44), (11, 0.57), (12, 0.63), (13, 6.65), (14, 0.28), (15, 1.38), (16, 1.89), (17, 0.63), (18, 0.21), (19, 0.62), (20, 0.21), (21, 0.21), (22, 0.91), (23, 1.04), (24, 0.27), (25, 1.19), (26, 0.36), (27, 0.33), (28, 0.19), (31, 0.51), (32, 0.35), (29, 0.44), (30, 0.32), (33, 0.25)),
    ('AggregationTask', 'rone'): ((3, 0.42), (4, 1.49), (5, 0.81), (6, 0.54), (7, 2.07), (8, 0.26), (34, 3.85), (10, 0.32), (12, 0.63), (13, 6.86), (14, 0.41), (15, 1.63), (16, 1.91), (17, 0.68), (18, 0.38), (19, 0.53), (20, 0.2), (21, 0.17), (22, 0.74), (0, 0.3), (1, 0.52), (2, 0.65), (29, 0.46), (30, 0.31), (31, 0.6), (32, 0.3)),
    ('FlockingTask', 'epuck'): ((0, 0.45), (1, 0.95), (2, 1.28), (3, 0.57), (4, 1.71), (5, 0.72), (6, 0.58), (7, 2.18), (8, 0.4), (9, 5.28), (10, 0.46), (11, 0.54), (12, 0.55), (13, 7.06), (14, 0.29), (15, 1.69), (16, 2.5), (17, 0.91), (18, 0.23), (35, 0.28), (20, 0.3), (21, 0.22), (22, 1.05), (23, 0.96), (24, 0.23), (25, 0.75), (26, 0.52), (27, 0.28), (28, 0.18), (29, 0.41), (30, 0.48), (31, 0.44), (32, 0.5), (33, 0.29)),
    ('CentroidSeekingTask', 'epuck'): ((3, 0.51), (4, 1.84), (5, 0.78), (6, 0.4), (7, 1.8), (8, 0.3), (9, 4.35), (10, 0.31), (11, 0.63), (12, 0.54), (13, 6.45), (14, 0.32), (15, 1.77), (16, 1.69), (17, 0.89), (20, 0.23), (21, 0.2), (22, 0.67), (0, 0.57), (1, 0.7), (2, 0.75), (23, 0.93), (24, 0.22), (25, 0.72), (26, 0.25), (27, 0.21), (28, 0.3), (31, 0.51), (32, 0.23), (29, 0.46), (30, 0.32), (33, 0.23)),
    ('SortedFollowingTask', 'rone'): ((3, 0.44), (4, 1.55), (5, 0.86), (6, 0.48), (7, 1.47), (8, 0.27), (34, 3.76), (10, 0.26), (12, 0.72), (13, 6.37), (14, 0.29), (15, 1.27), (16, 1.69), (17, 0.63), (20, 0.38), (21, 0.19), (22, 0.6), (2, 0.63), (33, 0.82), (36, 0.25), (0, 0.56), (1, 0.75), (32, 0.33), (29, 0.3), (30, 0.5)),
    ('ParityClusteringTask', 'rone'): ((3, 0.44), (4, 1.7), (5, 1.11), (6, 0.6), (7, 1.77), (8, 0.29), (34, 5.73), (10, 0.4), (12, 0.97), (13, 7.97), (14, 0.34), (15, 1.25), (16, 1.74), (17, 0.67), (18, 0.48), (19, 0.78), (20, 0.28), (21, 0.2), (22, 0.96), (2, 0.72), (0, 0.29), (1, 0.67), (33, 0.55), (36, 0.16), (32, 0.38), (29, 0.33), (30, 0.38)),
    ('MidAngleNavigationTask', 'rone'): ((3, 0.48), (4, 1.61), (5, 0.78), (6, 0.45), (7, 1.72), (8, 0.28), (34, 3.89), (12, 0.75), (13, 6.65), (14, 0.34), (15, 1.37), (16, 1.82), (17, 0.69), (20, 0.31), (21, 0.17), (22, 0.85), (2, 0.65), (33, 0.76), (36, 0.17), (0, 0.35), (1, 0.75), (32, 0.23), (29, 0.34), (30, 0.48)),
}
