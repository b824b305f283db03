"""What belongs to MuJoCo rather than to a script: its envs' whole state for an exact
--resume (MujocoEnvState), the GIFs' and the window's camera that follows the agent,
Reacher's fingertip distance, and the check that an env id is a MuJoCo one. The MuJoCo
scripts hand these to the tools.
"""

import gymnasium as gym
import numpy as np
import torch

import cli
import common

# GIFs look through the model's "track" camera, which follows the walker (gymnasium's
# default free camera stays put, and a walking agent leaves the picture). Models without
# such a camera (InvertedPendulum) keep the default view. 1000 steps -> every 4th frame,
# 250 frames, at half size: a GIF of a few MB.
GIF = dict(max_frames=250, every=4, scale=2, camera_name="track")


def gif_for(env_id):
    """GIF's settings for `env_id`: every 4th frame of a 1000-step episode at half size; every
    frame of a short one (Reacher's 50 steps) at full size, where the arm is small; at most 250
    frames."""
    steps = gym.spec(env_id).max_episode_steps or 1000
    every = max(1, min(4, steps // GIF["max_frames"]))
    return dict(GIF, every=every, scale=GIF["scale"] if every > 1 else 1)


class MujocoEnvState:
    """A MuJoCo env mid-episode as a state_dict(): the simulator's whole state (positions,
    velocities, the solver's warm start), the generator used at reset, and the wrappers'
    counters (the time limit's steps, the episode's return and length so far)."""

    COUNTERS = ("_elapsed_steps", "episode_returns", "episode_lengths")

    def __init__(self, env, counters=COUNTERS):
        self.env, self.counters = env, counters

    def state_dict(self):
        import mujoco

        sim, what = self.env.unwrapped, mujoco.mjtState.mjSTATE_INTEGRATION
        state = np.empty(mujoco.mj_stateSize(sim.model, what))
        mujoco.mj_getState(sim.model, sim.data, state, what)
        return dict(mujoco=torch.from_numpy(state), rng=sim.np_random.bit_generator.state,
                    **{name: float(self.env.get_wrapper_attr(name)) if name == "episode_returns"
                       else int(self.env.get_wrapper_attr(name)) for name in self.counters})

    def load_state_dict(self, saved):
        import mujoco

        sim = self.env.unwrapped
        mujoco.mj_setState(sim.model, sim.data, saved["mujoco"].numpy(),
                           mujoco.mjtState.mjSTATE_INTEGRATION)
        sim.np_random.bit_generator.state = saved["rng"]
        for name in self.counters:
            self.env.set_wrapper_attr(name, saved[name])


class MujocoVecEnvState:
    """gym.make_vec's MuJoCo envs (under RecordEpisodeStatistics, common.make_vec_env) mid-
    episode as a state_dict(): each env's MujocoEnvState (its time limit's counter), which envs
    reset at their next step (NEXT_STEP autoreset), and the episodes' returns and lengths so far."""

    STATS = ("episode_returns", "episode_lengths", "prev_dones")

    def __init__(self, envs):
        self.envs = envs

    def state_dict(self):
        vec = self.envs.unwrapped
        return dict(envs=[MujocoEnvState(env, ("_elapsed_steps",)).state_dict()
                          for env in vec.envs],
                    autoreset=torch.from_numpy(vec._autoreset_envs.copy()),
                    **{name: torch.from_numpy(np.array(getattr(self.envs, name)))
                       for name in self.STATS})

    def load_state_dict(self, saved):
        vec = self.envs.unwrapped
        if len(saved["envs"]) != len(vec.envs):
            raise ValueError(f"{len(saved['envs'])} envs saved, {len(vec.envs)} made")
        for env, state in zip(vec.envs, saved["envs"]):
            MujocoEnvState(env, ("_elapsed_steps",)).load_state_dict(state)
        vec._autoreset_envs = saved["autoreset"].numpy().copy()
        for name in self.STATS:
            setattr(self.envs, name, saved[name].numpy().copy())


def reacher_distance(trajectories):
    """Reacher: the fingertip's mean distance to the target at the last step of evaluation
    episodes (common.evaluate's trajectories), from the obs the last action was chosen in
    (Reacher-v5's ends with fingertip - target, x and y); nan for another env."""
    last = [episode["obs"][-1] for episode in trajectories]
    if not last or len(last[0]) != 10:  # Reacher-v5's obs has 10 numbers
        return float("nan")
    return float(np.mean([np.linalg.norm(obs[-2:]) for obs in last]))


def watch_camera(env_id):
    """gym.make arguments for --watch: the window's camera follows the agent. (The window
    ignores camera_name; it takes the env's own view settings, here with a tracking type.)"""
    import mujoco

    with common.env_errors(env_id):
        env = gym.make(env_id)
    view = dict(env.unwrapped.mujoco_renderer.default_cam_config or {})
    env.close()
    return dict(default_camera_config={**view, "type": mujoco.mjtCamera.mjCAMERA_TRACKING})


def check_mujoco(env_id):
    """A gymnasium env that is not a MuJoCo one is refused (from its registration; no env is
    made). Other ids: train() says what is wrong with them."""
    try:
        entry = gym.spec(env_id).entry_point
    except gym.error.Error:
        return  # unknown: train() says so, with gymnasium's suggestion
    if isinstance(entry, str) and entry.startswith("gymnasium.envs."):
        cli.check(entry.startswith("gymnasium.envs.mujoco"),
                  f"{env_id} is not a MuJoCo env; this script trains MuJoCo tasks (Walker2d-v5, "
                  "Hopper-v5, HalfCheetah-v5, InvertedPendulum-v5, ...)")
