"""Exercise: DDPG's actor loss, the deterministic policy gradient (Silver et al. 2014;
Lillicrap et al. 2016, Algorithm 1).

From tutorial 003: the actor ascends Q(s, mu(s)); autograd through the critic's action input
gives grad_a Q * grad mu. The states come from the replay buffer; the action is the actor's
own, mu(s), not the one stored.

    python exercises/check.py actor_loss
The reference answer: ddpg_walker.compute_loss_actor (ddpg_walker.py).

练习：DDPG 演员的损失，即确定性策略梯度（Silver 等 2014；Lillicrap 等 2016 的算法 1；对照
教程 003）。演员要提高 Q(s, mu(s))，所以损失是
-Q 的均值；动作用演员自己的 mu(s)，不是缓冲区里存的动作。参考答案：ddpg_walker.compute_loss_actor。
"""


def compute_loss_actor(actor, critic, obs):
    """-mean over the batch of Q(s, mu(s)): critic(obs, actions) gives (B,), actor(obs) the
    actions (B, act_dim). Returns a 0-dim tensor whose gradient reaches the actor.

    Q(s, mu(s)) 在小批量上的均值取负：critic(obs, actions) 给出 (B,)，actor(obs) 给出动作
    (B, act_dim)。返回一个 0 维张量，它的梯度要能传到演员。
    """
    # Your code here (你的代码写在这里)
    raise NotImplementedError("not written yet")
