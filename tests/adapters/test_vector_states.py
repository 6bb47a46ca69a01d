"""SwarmVectorEnv.states(): row b is SwarmEnv.state() of a single env in copy b's place, bit for bit."""

import numpy as np
import pytest

import swarm_envs


@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
@pytest.mark.parametrize("sensing", ["ideal", "full"])
def test_states_equal_single_env_states_over_an_episode_end(env_id, sensing):
    B, N, T = 3, 4, 5
    vec = swarm_envs.make_vec(env_id, B, n_robots=N, max_cycles=T, sensing=sensing)
    with pytest.raises(RuntimeError, match="reset"):
        vec.states()
    vec.reset(seed=20)
    singles = [swarm_envs.make(env_id, n_robots=N, max_cycles=T, sensing=sensing) for _ in range(B)]
    for b, single in enumerate(singles):
        single.reset(seed=20 + b)
    rng = np.random.default_rng(0)
    for t in range(T):
        states = vec.states()
        assert states.dtype == np.float32 and states.shape == (B, *singles[0].state_space.shape)
        for b, single in enumerate(singles):
            np.testing.assert_array_equal(states[b], single.state(), err_msg=f"step {t}, copy {b}")
        actions = rng.uniform(-1, 1, (B, N, vec.layout.action_size))
        vec.step(actions)
        for b, single in enumerate(singles):
            single.step({agent: actions[b, i] for i, agent in enumerate(single.possible_agents)})
    np.testing.assert_array_equal(vec.states()[:, -1], 1.0)  # progress at the last step
    vec.step(np.zeros((B, N, vec.layout.action_size)))  # NEXT_STEP autoreset: every copy starts again (generators continue)
    for b, single in enumerate(singles):
        single.reset()
        np.testing.assert_array_equal(vec.states()[b], single.state())
