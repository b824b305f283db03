"""Exercise: the soft target update (Lillicrap et al. 2016, Algorithm 1).

From tutorial 003: after each update, every parameter of a target network moves a fraction
tau toward the network's: theta' <- tau * theta + (1 - tau) * theta'.

    python exercises/check.py soft_update
The reference answer: ddpg_walker.soft_update (ddpg_walker.py).

练习：目标网络的软更新（Lillicrap 等 2016 的算法 1，对照教程 003）。每次更新后，目标网络的每个参数向当前网络移动
tau 的比例：theta' <- tau * theta + (1 - tau) * theta'。参考答案：ddpg_walker.soft_update。
"""

import torch


@torch.no_grad()
def soft_update(target, source, tau):
    """Move each parameter of `target` (a torch module) toward the same parameter of `source`,
    in place; `source` is left as it is.

    把 target（一个 torch 模块）的每个参数原地移向 source 里对应的参数；source 保持不变。
    """
    # Your code here (你的代码写在这里): a loop over zip(target.parameters(), source.parameters())
    raise NotImplementedError("not written yet")
