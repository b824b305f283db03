"""Loop exercise: PPO's rollout step, the lines of train() that store one step of the N
envs of a vector env and move on, with the autoreset mask and what makes the bootstrap right.

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

中文：循环练习：PPO 采集数据的一步，即 train() 里把向量环境里 N 个环境的这一步存起来、
再往前走的那几行，包括自动重置步的掩码，以及让自举正确的那些细节。
gymnasium 1.x 的向量环境会自己重置，模式是 NEXT_STEP：回合结束后的
下一步是重置步，它的动作被忽略，奖励是 0，观测是新回合的第一个观测。所以第 t + 1 步存下的观测
就是第 t 步到达的观测，回合结束之后也是（那时它是那个回合真正的最后一个观测）。
这批数据采完之后，GAE 从下一个存下的观测读 V(s_{t+1})，只在时间截断处用它自举（common.gae），更新时
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

    把 N 个环境的第 t 步存起来，返回（第 t + 1 步所在的观测，第 t + 1 步的自动重置掩码）。
    obs、next_obs 是形状为 (N, obs_dim) 的 numpy 数组；action、reward、terminated、truncated
    的形状都是 (N,)，按环境返回的原样传进来（reward 已经缩放过）；autoreset 是 (N,) 的布尔数组，
    上一步结束了回合的环境为 True，这样第 t 步就是那个环境的重置步。
    buffer.store(t, obs, action, reward, terminated, truncated, valid) 写入第 t 行，参数就按
    这个顺序；valid 的形状是 (N,)，不能拿来训练的行（重置步）为 False。返回值是 (next_obs,
    第 t + 1 步的掩码)：这一步结束了回合（终止或时间截断）的环境为 True。
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
