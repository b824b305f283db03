"""Loop exercise: DDPG's store-and-advance step, the lines of train() between env.step() and
the update.

The loop has just acted in obs and stepped the env: next_obs, reward, terminated, truncated
came back. Store the transition in the replay buffer and hand the loop the obs its next
action is chosen in. The traps are the loop's: store terminated, not (terminated or
truncated), since a time-limit truncation is not terminal and its TD target must still
bootstrap from Q'(s', mu'(s')); keep obs and next_obs apart (the action was chosen in obs);
after an episode ends (either way) the next action starts from a new episode. DDPG steps one
env and resets it by hand (tutorial 003): there is no autoreset step to skip.

    python exercises/check.py ddpg_store_step
The reference answer: ddpg_walker.store_and_advance (ddpg_walker.py).

中文：循环练习：DDPG 的“存储并前进”一步，即 train() 里 env.step() 之后、更新之前的那几行。循环刚在
obs 上选了动作、走了一步，环境返回了 next_obs、reward、terminated、truncated。把这个转移存进回放
缓冲区，再告诉循环下一个动作要在哪个观测上选。陷阱都在循环里：存 terminated，不是 terminated or
truncated，因为时间截断不是终止，它的 TD 目标还要用 Q'(s', mu'(s')) 自举；obs 和 next_obs 不能弄混
（动作是在 obs 上选的）；回合结束后（不管是终止还是时间截断），下一个动作从新回合开始。DDPG 只有一个
环境，由循环自己重置（和教程 003 一样），所以没有要跳过的自动重置步。
参考答案：ddpg_walker.store_and_advance。
"""


def store_and_advance(env, buffer, obs, action, reward, next_obs, terminated, truncated):
    """Store the transition and return the obs the next action is chosen in.

    buffer.add(obs, action, reward, next_obs, terminated) stores one transition; its last
    argument says whether the episode really ended (the buffer keeps not_done = 1 - it).
    env.reset() starts a new episode and returns (first obs, info). Return next_obs, or,
    once this episode has ended (terminated or truncated), the new episode's first obs.
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
