"""What a run plays and shows: the solved rule's second half (pi as it is now plays its check),
the pictures (curve.png, inside.png with CartPole's maps of V and pi beside the true V), the
evaluations and GIFs at the end of a run, model.pt / best.pt / best.gif at DDPG's
evaluations, and --eval / --watch / --gif playback.
"""

import time
from dataclasses import asdict

import gymnasium as gym
import numpy as np
import torch

import checkpoints
import common
import plots

# GIFs look through the model's "track" camera, which follows the walker (gymnasium's
# default free camera stays put, and a walking agent leaves the picture). Models without
# such a camera (InvertedPendulum) keep the default view. 1000 steps -> every 4th frame,
# 250 frames, at half size: a GIF of a few MB.
CAMERA = dict(camera_name="track")
GIF = dict(max_frames=250, every=4, scale=2)


def pi_holds(logits_of, device, cfg, threshold, step):
    """Does pi, as it is now, also reach `threshold`: the mean return of cfg.eval_episodes
    episodes, actions drawn from pi, env and draws seeded with eval_seed + 1 (apart from
    training and from the evaluation after it)? Says what it found in one line."""
    returns = common.evaluate(cfg.env_id, common.pi_actions(logits_of, device, cfg.eval_seed + 1),
                              cfg.eval_episodes, cfg.eval_seed + 1)
    held = np.mean(returns) >= threshold
    print(f"check at step {step}: pi as it is now averages {np.mean(returns):.1f} over "
          f"{len(returns)} episodes: " + ("it holds, training stops" if held else
                                         f"below {threshold:g}, training goes on"), flush=True)
    return held


def cartpole_grid(n):
    """CartPole states on an n x n grid of pole angle (+-0.21 rad, where an episode ends) and
    angular velocity (+-2 rad/s), the cart at rest in the middle: (angle, velocity, obs)."""
    angle, velocity = np.linspace(-0.21, 0.21, n), np.linspace(-2.0, 2.0, n)
    a, v = np.meshgrid(angle, velocity)  # rows: velocity, columns: angle
    return angle, velocity, np.stack([np.zeros(a.size), np.zeros(a.size), a.ravel(), v.ravel()], 1)


def cartpole_maps(logits_of, value_of, device, n=41):
    """V(s) and pi(push right | s) on cartpole_grid(n), from obs -> logits and obs -> V."""
    angle, velocity, obs = cartpole_grid(n)
    with torch.no_grad():
        x = torch.as_tensor(obs, dtype=torch.float32, device=device)
        right, values = torch.softmax(logits_of(x), -1)[:, 1], value_of(x)
    return dict(angle=angle, velocity=velocity, value=values.reshape(n, n).cpu().numpy(),
                right=right.reshape(n, n).cpu().numpy())


def cartpole_true_values(logits_of, device, gamma, reward_scale, seed, n=11, rollouts=10):
    """The truth beside the learned V(s): V^pi(s), the expected discounted return of pi from
    s, by Monte-Carlo: from each state of cartpole_grid(n), `rollouts` episodes with actions
    drawn from pi, all at once in gymnasium's vectorized CartPole, without a time limit, each
    followed until it terminates or gamma^t < 0.001 (the rest: under 0.1% of the largest
    return). Rewards scaled as the script scales them. Returns {"angle", "velocity", "value"}."""
    from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv

    angle, velocity, start = cartpole_grid(n)
    envs = CartPoleVectorEnv(num_envs=n * n * rollouts, max_episode_steps=10**9)
    envs.reset(seed=seed)
    envs.state = np.repeat(start.T, rollouts, axis=1)  # each state `rollouts` times, in a row
    rng, obs = np.random.default_rng(seed), envs.state.T.astype(np.float32)
    alive, total, discount = np.ones(envs.num_envs, dtype=bool), np.zeros(envs.num_envs), 1.0
    while alive.any() and discount >= 1e-3:
        with torch.no_grad():
            logits = logits_of(torch.as_tensor(obs, device=device))
        probs = torch.softmax(logits.double(), -1).cpu().numpy()
        action = (rng.random((len(probs), 1)) > probs.cumsum(1)).sum(1)  # a ~ pi(.|s)
        obs, reward, terminated, _, _ = envs.step(np.minimum(action, probs.shape[1] - 1))
        total += alive * discount * reward_scale * reward  # the step that ends still counts
        alive &= ~terminated
        discount *= gamma
    envs.close()
    return dict(angle=angle, velocity=velocity,
                value=total.reshape(n * n, rollouts).mean(1).reshape(n, n))


def draw_inside(run, nets, device, reward_scale):
    """inside.png (plots.draw_inside): what the updates did and, on CartPole, V(s) and
    pi(right|s) untrained and trained, the true V of the trained pi and the states visited,
    also kept in maps.npz. `nets`: {"untrained"/"trained": (obs -> logits, obs -> V)}."""
    cfg, maps = run.cfg, None
    if cfg.env_id.startswith("CartPole"):
        maps = {when: cartpole_maps(*fns, device) for when, fns in nets.items()}
        maps["true"] = true = cartpole_true_values(nets["trained"][0], device, cfg.gamma,
                                                   reward_scale, cfg.eval_seed)
        maps["visited"] = visited = (np.concatenate(run.visited)[:, 2:4] if run.visited
                                     else np.zeros((0, 2)))  # (pole angle, angular velocity)
        with common.written_whole(run.dir / "maps.npz") as tmp, open(tmp, "wb") as f:
            np.savez(f, **{f"{when}_{key}": maps[when][key] for when in ("untrained", "trained")
                           for key in ("value", "right")},
                     angle=maps["trained"]["angle"], velocity=maps["trained"]["velocity"],
                     true_value=true["value"], true_angle=true["angle"],
                     true_velocity=true["velocity"], visited=visited)
    return plots.draw_inside(run.dir, run.script, asdict(cfg), run.kept, maps)


def finish_cartpole(run, threshold, nets, device, reward_scale):
    """After a CartPole script's training: curve.png, inside.png (draw_inside's `nets`),
    TensorBoard, two evaluations (actions drawn from pi, and pi's most probable action) and
    the GIFs. Returns train()'s result: run_dir, solved, solved_step, global_step,
    episode_returns, eval_returns, greedy_returns, interrupted."""
    cfg, run_dir, step = run.cfg, run.dir, run.global_step
    result = dict(run_dir=run_dir, solved=run.solved_step is not None,
                  solved_step=run.solved_step, global_step=step,
                  episode_returns=[r for _, r in run.episodes], eval_returns=[],
                  greedy_returns=[], interrupted=run.interrupted)
    if run.interrupted:  # the curve so far and where everything is; main() exits with 130
        if cfg.curves and (run_dir / "progress.csv").exists():
            with common.ctrl_c_deferred():  # a second Ctrl-C waits for the picture
                plots.draw_run(run_dir, threshold, run.solved_step, cfg.solved_window)
        print(f"\ninterrupted at step {step}: {run_dir} holds "
              f"{', '.join(sorted(f.name for f in run_dir.iterdir()))} "
              f"(replay: python {run.script}.py --eval {run_dir})", flush=True)
        return result
    elapsed = time.time() - run.start_time
    print(f"trained {step} steps, {len(run.episodes)} episodes in {elapsed:.1f}s; "
          f"model: {run_dir / 'model.pt'}", flush=True)
    if cfg.curves:
        with common.ctrl_c_deferred():  # Ctrl-C waits until the pictures are whole
            curve = plots.draw_run(run_dir, threshold, run.solved_step, cfg.solved_window)
            print(f"curve: {curve}\ninside: {draw_inside(run, nets, device, reward_scale)}",
                  flush=True)
    if cfg.tensorboard:
        plots.to_tensorboard(run_dir, sps=step / elapsed)
    # Two evaluations of the same episode seeds: actions drawn from pi, as in training (the
    # policy that "solved" judged), and pi's most probable action (greedy). They can differ
    # either way: a policy trained to be sampled need not be good when it is not.
    n, seed, logits_of = cfg.eval_episodes, cfg.eval_seed, nets["trained"][0]
    for key, greedy, what in (("eval_returns", False, "actions drawn from pi"),
                              ("greedy_returns", True, "pi's most probable action")):
        act = common.pi_actions(logits_of, device, seed, greedy=greedy)
        result[key] = returns = common.evaluate(cfg.env_id, act, n, seed)
        print(f"{'greedy ' if greedy else ''}evaluation over {n} episodes, {what}: mean "
              f"{np.mean(returns):.1f}, min {min(returns):.0f}", flush=True)
    if cfg.gifs:  # one episode each, drawn from pi: after.gif shows the evaluation's first
        for name, when in (("before.gif", "untrained"), ("after.gif", "trained")):
            act = common.pi_actions(nets[when][0], device, seed)  # every 2nd frame, half size
            ret = common.record_gif(cfg.env_id, act, run_dir / name, seed, every=2, scale=2)
            print(f"{name}: return {ret:.0f} -> {run_dir / name}", flush=True)
    return result


def saved_model(result):
    """train()'s result -> its run folder (its model.pt, for --watch); after a Ctrl-C, which
    train() has already reported with what it saved, exit 130 instead."""
    if result["interrupted"]:
        raise SystemExit(130)
    return str(result["run_dir"])


def after_evaluation(run, actor, best, device, info):
    """DDPG's files at each evaluation: model.pt (the actor, `info` to rebuild it), and best.pt
    and best.gif if it is the best so far; curve.png and inside.png redrawn; TensorBoard."""
    cfg = run.cfg
    checkpoints.save_model(run.dir / "model.pt", run.script, cfg, run.evaluations[-1][0],
                           {"actor": actor}, **info)
    if best:
        checkpoints.save_model(run.dir / "best.pt", run.script, cfg, run.evaluations[-1][0],
                               {"actor": actor}, **info)
        if cfg.gifs:
            common.record_gif(cfg.env_id, common.deterministic(actor, device),
                              run.dir / "best.gif", cfg.eval_seed, **GIF, **CAMERA)
    if cfg.curves:
        plots.draw_run(run.dir)  # rewritten at every evaluation: open it any time
        plots.draw_inside(run.dir, run.script, asdict(cfg))
    if cfg.tensorboard:
        plots.to_tensorboard(run.dir, sps=run.timer["rate"])
    run.clock_from(run.evaluations[-1][0])  # the next steps/s: learning, not this


def finish_walker(run, global_step, interrupted, untrained, actor, device):
    """After DDPG's loop: where a stopped run is and how to go on, or the learning phase's
    steps/s and the before/after GIFs. Returns train()'s result: run_dir, global_step,
    evaluations, episodes, steps_per_second (learning phase) and interrupted."""
    learned_from, since = run.timer.get("learning_since", (global_step, time.time()))
    learned = global_step - learned_from
    rate = learned / (time.time() - since) if learned > 0 else float("nan")
    result = dict(run_dir=run.dir, global_step=global_step, evaluations=run.evaluations,
                  episodes=run.episodes, steps_per_second=rate, interrupted=interrupted)
    if interrupted:
        path = run.dir / "checkpoint.pt"
        saved = (torch.load(path, weights_only=True, mmap=True)["global_step"]
                 if path.exists() else None)
        where = (f"its checkpoint is at step {saved}: continue with `python {run.script}.py "
                 f"--resume {run.dir}`" if saved else "no checkpoint was written yet")
        print(f"interrupted at step {global_step}; {where} (before.gif and after.gif come "
              f"when a run finishes; best.gif shows its best evaluation so far)", flush=True)
        return result
    print(f"learning phase: {learned} steps at {rate:.1f} steps/s (updates and evaluations "
          f"included); run folder: {run.dir}", flush=True)
    if run.cfg.gifs:
        for name, net in (("before.gif", untrained), ("after.gif", actor)):
            ret = common.record_gif(run.cfg.env_id, common.deterministic(net, device),
                                    run.dir / name, run.cfg.eval_seed, **GIF, **CAMERA)
            print(f"{name}: return {ret:.0f} -> {run.dir / name}", flush=True)
    return result


def play_policy(cfg, path, env_id, logits_of):
    """--eval: play cfg.eval_episodes episodes of a saved CartPole policy (obs -> logits),
    actions drawn from pi (in a window with --watch), then as many greedy ones; returns the
    first ones' returns. With --gif: one episode, drawn as after.gif is, to that file."""
    act = common.pi_actions(logits_of, "cpu", cfg.eval_seed)
    if cfg.gif:
        ret = common.record_gif(env_id, act, cfg.gif, cfg.eval_seed, every=2, scale=2)
        print(f"{cfg.gif}: one episode, return {ret:.0f}", flush=True)
        return [ret]
    print(f"playing {cfg.eval_episodes} episodes of {env_id} with {path}"
          + ("; Ctrl-C stops" if cfg.watch else ""), flush=True)
    returns = common.evaluate(env_id, act, cfg.eval_episodes, cfg.eval_seed,
                              render_mode="human" if cfg.watch else None, log=cfg.watch)
    print(f"{env_id}, {path}: returns {[round(r) for r in returns]}, "
          f"mean {np.mean(returns):.1f} (actions drawn from pi)", flush=True)
    greedy = common.evaluate(env_id, common.pi_actions(logits_of, "cpu", cfg.eval_seed, True),
                             cfg.eval_episodes, cfg.eval_seed)
    print(f"greedy (pi's most probable action): returns {[round(r) for r in greedy]}, "
          f"mean {np.mean(greedy):.1f}", flush=True)
    return returns


def play_actor(cfg, path, env_id, actor):
    """--eval: play cfg.eval_episodes episodes of a saved DDPG actor without noise (in a window
    with --watch, its camera following the agent), or with --gif one episode to that file."""
    policy = common.deterministic(actor, torch.device("cpu"))
    if cfg.gif:
        print(f"recording one episode of {env_id} with {path} (up to a minute)", flush=True)
        ret = common.record_gif(env_id, policy, cfg.gif, cfg.eval_seed, **GIF, **CAMERA)
        print(f"{cfg.gif}: one episode, return {ret:.1f}", flush=True)
        return [ret]
    print(f"playing {cfg.eval_episodes} episodes of {env_id} with {path}"
          + ("; Ctrl-C stops" if cfg.watch else ""), flush=True)
    returns = common.evaluate(env_id, policy, cfg.eval_episodes, cfg.eval_seed,
                              render_mode="human" if cfg.watch else None, log=cfg.watch,
                              **(watch_camera(env_id) if cfg.watch else {}))
    print(f"{env_id}, {path}: returns {[round(r, 1) for r in returns]}, "
          f"mean {np.mean(returns):.1f}", flush=True)
    return returns


def watch_camera(env_id):
    """gym.make arguments for --watch: the window's camera follows the agent. (The window
    ignores camera_name; it takes the env's own view settings, here with a tracking type.)"""
    import mujoco

    with common.env_errors(env_id):
        env = gym.make(env_id)
    view = dict(env.unwrapped.mujoco_renderer.default_cam_config or {})
    env.close()
    return dict(default_camera_config={**view, "type": mujoco.mjtCamera.mjCAMERA_TRACKING})


def finish_grpo(run, samples, cfg):
    """After GRPO's run: its pictures (draw_grpo) and TensorBoard, as asked."""
    if cfg.curves:
        with common.ctrl_c_deferred():  # Ctrl-C waits until the pictures are whole
            draw_grpo(run, samples, cfg)
    if cfg.tensorboard:
        plots.to_tensorboard(run.dir)


def draw_grpo(run, samples, cfg):
    """GRPO's pictures. curve.png: the reward of the sampled completions, held-out pass@1, the
    KL to pi_ref and the share of groups whose rewards are all equal (no signal), over the
    steps. inside.png: the per-token ratio pi / pi_old at three GRPO updates against the
    clip band, and held-out prompts' completions before and after GRPO (x: wrong)."""
    plt, log = plots.pyplot(), plots.read_csv(run.dir / "progress.csv")
    x, checked = log["global_step"], np.isfinite(log["pass1"])
    fig, axes = plt.subplots(2, 2, figsize=(10, 5.5), gridspec_kw=dict(width_ratios=[1, 2]))
    second = "more supervision" if cfg.control else "GRPO"
    for column, (phase, steps) in enumerate((("supervised", x <= cfg.sft_steps),
                                             (second, x > cfg.sft_steps))):
        top, bottom = axes[:, column]  # each phase on its own step axis: GRPO's is shorter
        if not cfg.control and column == 1:
            top.plot(x[steps], log["reward"][steps], color="C0", lw=0.8,
                     label="reward of the samples")
            bottom.plot(x[steps], log["kl"][steps], color="C4", lw=0.8,
                        label="KL(pi || pi_ref), k3")
            bottom.plot(x[steps], log["flat_groups"][steps], color="C7", lw=0.8,
                        label="groups with equal rewards (no signal)")
        else:
            bottom.plot(x[steps & checked], log["loss"][steps & checked], color="C1", lw=1,
                        label="cross-entropy")
        top.plot(x[steps & checked], log["pass1"][steps & checked], "o-", color="C3", ms=3,
                 label="held-out pass@1 (100 sums)")
        top.set_title(phase, fontsize=9)
        bottom.set_xlabel("step")
        for ax in (top, bottom):
            ax.legend(fontsize=7)
    fig.suptitle(run.dir.name, fontsize=8)
    fig.tight_layout()
    print(f"curve: {plots.save_whole(plt, fig, run.dir / 'curve.png', dpi=90)}", flush=True)
    fig = plt.figure(figsize=(12, 8))
    grid = fig.add_gridspec(3, 3, hspace=0.5)
    updates = [k for k in run.kept if "ratio" in k[1]]  # none with --control
    for column, (update, step, arrays) in enumerate(plots.three_updates(updates) if updates else []):
        ax = fig.add_subplot(grid[0, column])
        ax.hist(arrays["ratio"], bins=40, color="C0")
        for v in (1 - cfg.clip_coef, 1 + cfg.clip_coef):
            ax.axvline(v, color="k", ls="--", lw=0.8)
        ax.set_title(f"per-token r = pi/pi_old, GRPO update {update}", fontsize=8)
    for row, when in enumerate(("before", "after"), start=1):
        ax = fig.add_subplot(grid[row, :])
        ax.axis("off")
        ax.set_title(f"{len(samples.get(when, []))} held-out sums, {cfg.group_size} sampled "
                     f"answers each (x: wrong), {when} "
                     f"{'GRPO' if not cfg.control else 'more supervision'}", fontsize=9)
        ax.text(0, 1, "\n".join(samples.get(when, [])), va="top", family="monospace", fontsize=8)
    print(f"inside: {plots.save_whole(plt, fig, run.dir / 'inside.png', dpi=72)}", flush=True)
