"""What a run plays and shows: the solved rule's second half (the policy as it is now plays
its check), the pictures at the end of a run (curve.png, inside.png: the panels a script
chooses, the maps an env helper makes), the evaluations and GIFs at the end, model.pt /
best.pt / best.gif at each evaluation of a script that evaluates, and --eval / --watch /
--gif playback. A policy is handed over as `play`: [(result key, what the actions are,
seed -> (obs -> action)), ...], the first of which the checks, the GIFs and --gif use.
"""

import time

import numpy as np
import torch

import checkpoints
import common
import plots

GIF = dict(every=2, scale=2)  # every 2nd frame at half size, unless a script gives its own


def sampled_and_greedy(logits_of, device):
    """`play` of a policy over discrete actions, obs -> logits: actions drawn from pi (as in
    training: what the solved rule judges) and pi's most probable action. The two can differ
    either way: a policy trained to be sampled need not be good when it is not."""
    return [("eval_returns", "actions drawn from pi",
             lambda seed: common.pi_actions(logits_of, device, seed)),
            ("greedy_returns", "pi's most probable action",
             lambda seed: common.pi_actions(logits_of, device, seed, greedy=True))]


def pi_holds(play, cfg, threshold, step):
    """Does the policy, as it is now, also reach `threshold`: the mean return of
    cfg.eval_episodes episodes, acting as play[0] does, env and draws seeded with
    eval_seed + 1 (apart from training and from the evaluation after it)? Says what it found
    in one line."""
    returns = common.evaluate(cfg.env_id, play[0][2](cfg.eval_seed + 1), cfg.eval_episodes,
                              cfg.eval_seed + 1)
    held = np.mean(returns) >= threshold
    print(f"check at step {step}: the policy as it is now ({play[0][1]}) averages "
          f"{np.mean(returns):.1f} over {len(returns)} episodes: "
          + ("it holds, training stops" if held else f"below {threshold:g}, training goes on"),
          flush=True)
    return held


def draw_pictures(run, pictures, top=None, maps=None):
    """curve.png (the panel `top`, then pictures["curve"]'s rows; without a `top`, its rows
    alone, each as high as inside.png's) and inside.png (pictures["inside"]'s rows, then
    `maps`' row if there are maps, kept in maps.npz too). Returns the two paths."""
    logs = plots.load_logs(run.dir, getattr(run, "kept", ()), run.labels,
                           getattr(run, "learning_starts", 0))  # its random warm-up, shaded
    rows = pictures.get("curve", [])
    if top is not None:  # the returns on top, the rows under it lower
        curve = plots.draw(run.dir, "curve.png", [[top], *rows], logs, width=7,
                           heights=[3.2] + [1.6] * len(rows), dpi=96)
    else:  # the rows alone
        curve = plots.draw(run.dir, "curve.png", rows, logs, width=10, dpi=96)
    rows = list(pictures.get("inside", []))
    if maps is not None:
        rows.append([plots.maps_row(maps)])
        with common.written_whole(run.dir / "maps.npz") as tmp, open(tmp, "wb") as f:
            np.savez(f, **{f"{when}_{key}": maps[when][key] for when in ("untrained", "trained")
                           for key in ("value", "policy")}, true_value=maps["true"]["value"],
                     **{k: maps[k] for k in ("x", "y", "xlabel", "ylabel", "value_label",
                                             "policy_label", "true_x", "true_y", "visited")})
    inside = plots.draw(run.dir, "inside.png", rows, logs) if rows else None
    return curve, inside


def draw_logged(run, pictures):
    """After the training of a script without an env, a Ctrl-C too: curve.png and inside.png
    of what was logged (draw_pictures, --curves) and its TensorBoard scalars (--tensorboard);
    nothing before the first logged row. After a Ctrl-C, the line that says where it stopped
    and what its folder holds (main() then exits with 130)."""
    if (run.dir / "progress.csv").exists():
        if run.cfg.tensorboard:
            plots.to_tensorboard(run.dir, tags=run.tags)
        if run.cfg.curves:
            with common.ctrl_c_deferred():  # Ctrl-C waits until the pictures are whole
                curve, inside = draw_pictures(run, pictures)
                print(f"curve: {curve}\ninside: {inside}", flush=True)
    if run.interrupted:
        interrupted_at(run, run.global_step, "--eval uses its model.pt, as training left it")


def interrupted_at(run, step, then, when=""):
    """The last line after a Ctrl-C: the step (and `when`), the files the run folder holds,
    what next."""
    print(f"\ninterrupted at {getattr(run, 'unit', 'step')} {step}{when}: {run.dir} holds "
          f"{', '.join(sorted(f.name for f in run.dir.iterdir()))} "
          f"({then}: python {run.script}.py --eval {run.dir})", flush=True)


def finish_updates(run, threshold, play, before, pictures, maps=None):
    """After the training of a script that updates on batches: curve.png and inside.png
    (draw_pictures; `maps`: None, or a function that makes the maps), TensorBoard, an
    evaluation of each way of acting in `play` and the GIFs (before.gif: acting as `before`,
    the untrained policy's `play`, does first). Returns train()'s result: run_dir, solved,
    solved_step, global_step, episode_returns, the keys of `play`, interrupted."""
    cfg, run_dir, step = run.cfg, run.dir, run.global_step
    result = dict(run_dir=run_dir, solved=run.solved_step is not None,
                  solved_step=run.solved_step, global_step=step,
                  episode_returns=[r for _, r in run.episodes],
                  **{key: [] for key, _, _ in play}, interrupted=run.interrupted)
    top = plots.episode_returns(cfg.solved_window, threshold, run.solved_step)
    if run.interrupted:  # the pictures so far and where everything is; main() exits with 130
        if cfg.curves and (run_dir / "progress.csv").exists():
            with common.ctrl_c_deferred():  # a second Ctrl-C waits for the pictures
                draw_pictures(run, pictures, top)
        interrupted_at(run, step, "replay")
        return result
    elapsed = time.time() - run.start_time
    short = cfg.total_timesteps - step if run.solved_step is None else 0
    why = (f" (whole rollouts only: the last {short} steps of --total-timesteps "
           f"{cfg.total_timesteps} make no whole one)" if short > 0 else "")
    print(f"trained {step} steps{why}, {len(run.episodes)} episodes in {elapsed:.1f}s; "
          f"model: {run_dir / 'model.pt'}", flush=True)
    try:  # a late Ctrl-C too ends with the line that says where the model is
        if cfg.curves:
            with common.ctrl_c_deferred():  # Ctrl-C waits until the pictures are whole
                curve, inside = draw_pictures(run, pictures, top, maps and maps())
                print(f"curve: {curve}\ninside: {inside}", flush=True)
        if cfg.tensorboard:
            plots.to_tensorboard(run_dir, sps=step / elapsed, tags=run.tags)
        # The evaluations, each of the same episode seeds, one per way of acting
        n, seed = cfg.eval_episodes, cfg.eval_seed
        for i, (key, what, act_of) in enumerate(play):
            result[key] = returns = common.evaluate(cfg.env_id, act_of(seed), n, seed)
            print(f"{'greedy ' if i else ''}evaluation over {n} episodes, {what}: mean "
                  f"{np.mean(returns):.1f}, min {min(returns):.0f}", flush=True)
        if cfg.gifs:  # an episode each, acting as play[0]: after.gif, the evaluation's first
            for name, act_of in (("before.gif", before[0][2]), ("after.gif", play[0][2])):
                ret = common.record_gif(cfg.env_id, act_of(seed), run_dir / name, seed, **GIF)
                print(f"{name}: return {shown(ret)} -> {run_dir / name}", flush=True)
    except KeyboardInterrupt:  # main() then exits with 130 (143 after a SIGTERM)
        result["interrupted"] = True
        interrupted_at(run, step, "replay", ", after training, before its evaluation and "
                       "GIFs were done")
    return result


def saved_model(result):
    """train()'s result -> its run folder (its model.pt, for --watch); after a Ctrl-C, which
    train() has already reported with what it saved, exit 130 instead (143 after a SIGTERM)."""
    if result["interrupted"]:
        raise SystemExit(common.stopped_by()[1])
    return str(result["run_dir"])


def after_evaluation(run, actor, best, device, info, pictures, gif=GIF):
    """At each evaluation of a script that evaluates: model.pt (the actor, `info` to rebuild
    it), and best.pt and best.gif if it is the best so far; curve.png and inside.png redrawn
    (pictures: the script's panels, as for draw_pictures); TensorBoard."""
    cfg, step = run.cfg, run.evaluations[-1]["global_step"]
    checkpoints.save_model(run.dir / "model.pt", run.script, cfg, step, {"actor": actor}, **info)
    if best:
        checkpoints.save_model(run.dir / "best.pt", run.script, cfg, step, {"actor": actor},
                               **info)
        if cfg.gifs:
            common.record_gif(cfg.env_id, common.deterministic(actor, device),
                              run.dir / "best.gif", cfg.eval_seed, **gif)
        else:  # resumed with --no-gifs: a best.gif would show an earlier best
            (run.dir / "best.gif").unlink(missing_ok=True)
    if cfg.curves:  # rewritten at every evaluation: open them any time
        draw_pictures(run, pictures, plots.evaluation_returns())
    if cfg.tensorboard:
        plots.to_tensorboard(run.dir, sps=run.timer["rate"], tags=run.tags)
    run.clock_from(step)  # the next steps/s: learning, not this


def finish_evaluations(run, global_step, interrupted, untrained, actor, device, info, gif=GIF):
    """After the loop of a script that evaluates: model.pt, the actor training ended with (at
    a Ctrl-C too, beside the checkpoint); where a stopped run is and how to go on, or the
    learning phase's steps/s and the before/after GIFs. Returns train()'s result: run_dir,
    global_step, evaluations (evaluations.csv's rows), episodes, steps_per_second (learning
    phase) and interrupted."""
    learned_from, since = run.timer.get("learning_since", (global_step, time.time()))
    timed = global_step - learned_from  # the clock starts as the phase's first step ends
    rate = timed / (time.time() - since) if timed > 0 else float("nan")
    learned = timed + getattr(run.cfg, "num_envs", 1) if timed > 0 else 0  # that step too
    result = dict(run_dir=run.dir, global_step=global_step, evaluations=run.evaluations,
                  episodes=run.episodes, steps_per_second=rate, interrupted=interrupted)
    checkpoints.save_model(run.dir / "model.pt", run.script, run.cfg, global_step,
                           {"actor": actor}, **info)
    if interrupted:
        path = run.dir / "checkpoint.pt"
        saved = (torch.load(path, weights_only=True, mmap=True)["global_step"]
                 if path.exists() else None)
        where = (f"its checkpoint is at step {saved}: continue with `python {run.script}.py "
                 f"--resume {run.dir}`" if saved else "no checkpoint was written yet")
        best = ("; best.gif shows its best evaluation so far" if (run.dir / "best.gif").exists()
                else "")  # not before an evaluation has drawn it
        print(f"interrupted at step {global_step}; model.pt holds the actor of that step; "
              f"{where} (before.gif and after.gif come when a run finishes{best})", flush=True)
        return result
    print(f"learning phase: {learned} steps at {rate:.1f} steps/s (updates and evaluations "
          f"included); model: {run.dir / 'model.pt'} (step {global_step}); run folder: "
          f"{run.dir}", flush=True)
    try:  # a late Ctrl-C too ends with the line that says where the model is
        if run.cfg.gifs:
            for name, net in (("before.gif", untrained), ("after.gif", actor)):
                ret = common.record_gif(run.cfg.env_id, common.deterministic(net, device),
                                        run.dir / name, run.cfg.eval_seed, **gif)
                print(f"{name}: return {shown(ret)} -> {run.dir / name}", flush=True)
    except KeyboardInterrupt:  # main() then exits with 130 (143 after a SIGTERM)
        result["interrupted"] = True
        interrupted_at(run, global_step, "replay", ", after training, while its before and "
                       "after GIFs were recorded")
    return result


def play(cfg, path, env_id, ways, gif=GIF, watch=None):
    """--eval: play cfg.eval_episodes episodes of a saved policy for each way of acting in
    `ways` (as `play`), the first in a window with --watch (`watch`: env_id -> gym.make's
    arguments for that window, if the env needs any); returns the first's returns. With
    --gif: one episode, acting as the first does, to that file."""
    what, act_of = ways[0][1], ways[0][2]
    if cfg.gif:
        print(f"recording one episode of {env_id} with {path} ({what})", flush=True)
        ret = common.record_gif(env_id, act_of(cfg.eval_seed), cfg.gif, cfg.eval_seed, **gif)
        print(f"{cfg.gif}: one episode, return {ret:.1f}", flush=True)
        return [ret]
    print(f"playing {cfg.eval_episodes} episode{'s' * (cfg.eval_episodes != 1)} of {env_id} "
          f"with {path}"
          + ("; Ctrl-C stops" if cfg.watch else ""), flush=True)
    first = None
    for i, (_, what, act_of) in enumerate(ways):
        window = cfg.watch and i == 0
        returns = common.evaluate(env_id, act_of(cfg.eval_seed), cfg.eval_episodes,
                                  cfg.eval_seed, render_mode="human" if window else None,
                                  log=window, **(watch(env_id) if window and watch else {}))
        shown = [int(r) if float(r).is_integer() else round(r, 1) for r in returns]
        print(f"{env_id}, {path}: returns {shown}, "
              f"mean {np.mean(returns):.1f} ({what})", flush=True)
        first = returns if first is None else first
    return first


def shown(ret):
    """A GIF's return as printed: whole numbers, one decimal under 10 (Reacher's -0.3 is not -0)."""
    return f"{ret:.0f}" if abs(ret) >= 10 else f"{ret:.1f}"
