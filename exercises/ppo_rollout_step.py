"""Loop exercise: PPO's rollout step, the lines of train() that store one step of N vector
envs and move on, with the autoreset mask and what makes the bootstrap right.

gymnasium 1.x's vector envs reset an env by themselves, in NEXT_STEP mode: the step after an
episode ends is a reset step, whose action is ignored, whose reward is 0 and whose obs is
the new episode's first. So the obs stored at step t + 1 is where step t led, even after a
done step (then it is that episode's real final observation). After the rollout, GAE reads
V(s_{t+1}) from the next stored obs and bootstraps from it at a time-limit truncation only
(common.gae), and the update drops the rows marked not valid. The traps: keep terminated
and truncated as the env gave them (a truncation stored as a termination stops the
bootstrap; a termination lost bootstraps after the episode really ended); mark the reset
step, not the step that ended the episode; the action belongs to obs, not next_obs.

    python exercises/check.py ppo_rollout_step
The reference answer: ppo_cartpole.store_and_advance (ppo_cartpole.py).

中文：循环练习：PPO 采集数据的一步，即 train() 里把 N 个向量环境的一步存起来、再往前走的那几行，
包括自动重置步的掩码，以及让自举正确的那些细节。gymnasium 1.x 的向量环境会自己重置，模式是
NEXT_STEP：回合结束后的下一步是重置步，它的动作被忽略，奖励是 0，观测是新回合的第一个观测。所以第
t + 1 步存下的观测就是第 t 步到达的观测，回合结束之后也是（那时它是那个回合真正的最后一个观测）。
rollout 采完之后，GAE 从下一个存下的观测读 V(s_{t+1})，只在时间截断处用它自举（common.gae），更新时
丢掉标成无效（valid = False）的行。陷阱：terminated 和 truncated 按环境给的原样存（把时间截断存成
终止，就不自举了；漏了终止，回合真正结束之后还在自举）；掩掉的是重置步，不是结束回合的那一步；动作
属于 obs，不属于 next_obs。参考答案：ppo_cartpole.store_and_advance。
"""


def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                      autoreset):
    """Store step t of the N envs and return (the obs step t + 1 acts in, its autoreset mask).

    obs, next_obs: (N, obs_dim) numpy arrays; action, reward, terminated, truncated: (N,) as
    the envs returned them (reward already scaled); autoreset: (N,) bool, True where the
    previous step ended an episode, so that step t is that env's reset step.
    buffer.store(t, obs, action, reward, terminated, truncated, valid) writes row t; valid
    (N,) is False where the row must not train (a reset step). Return (next_obs, the mask
    for step t + 1: True where this step ended an episode, by termination or truncation).
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
