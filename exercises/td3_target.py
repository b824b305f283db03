"""Exercise: TD3's critic target: clipped double Q with target policy smoothing (Fujimoto et
al. 2018, eq. 10, section 5.3 and Algorithm 1).

From the TD3 paper (the tutorials stop at DDPG): the target action is the target actor's,
smoothed with clipped Gaussian noise and kept inside the action box,
a~ = clip(mu'(s') + clip(eps, -c, c) * half_width, low, high), eps ~ N(0, sigma) (a~ is the
docs' ã, the noisy target action; sigma and c are in units of half_width); the target takes
the smaller of the two target critics at it,
y = r + gamma * (1 - terminated) * min(Q1'(s', a~), Q2'(s', a~)). The lines after the blank
are the script's own.

    python exercises/check.py td3_target
The reference answer: td3_walker.update_critics (td3_walker.py).

练习：TD3 评论员的目标，即裁剪双 Q 学习加目标策略平滑（Fujimoto 等 2018 的式 10、第 5.3 节
和算法 1）。
目标动作是目标演员的动作加上裁剪过的高斯噪声，再限制在动作范围内：
a~ = clip(mu'(s') + clip(eps, -c, c) * half_width, low, high)，eps ~ N(0, sigma)。
a~ 就是文档里的 ã，即加了噪声的目标动作；sigma 和 c 都以 half_width 为单位。
目标取两个目标评论员在 a~ 处较小的估计：
y = r + gamma * (1 - terminated) * min(Q1'(s', a~), Q2'(s', a~))。空白后面的代码和脚本里的一样。
参考答案：td3_walker.update_critics。
"""

import torch
import torch.nn.functional as F


def update_critics(nets, batch, half_width, low, high, cfg):
    """One step of both critics on a minibatch toward the clipped double-Q target.

    nets: "actor_target", "critic_target" (Q1'), "critic2_target" (Q2'), "critic", "critic2"
    and "critic_opt"; a critic is called as critic(obs, action) and gives (B,).
    batch: obs (B, obs_dim), action (B, act_dim), reward (B,), next_obs, not_done (B,: 1 -
    terminated). half_width: (high - low) / 2 per action dimension; low, high: the action box.
    cfg.target_noise is sigma and cfg.noise_clip is c, both in units of half_width:

        eps = clip(N(0, sigma), -c, c) * half_width        (torch.randn_like(action))
        a~  = clip(mu'(s') + eps, low, high)
        y   = r + gamma * not_done * min(Q1'(s', a~), Q2'(s', a~))

    在一个小批量上让两个评论员朝裁剪双 Q 目标各走一步。nets 里有 "actor_target"、"critic_target"
    （Q1'）、"critic2_target"（Q2'）、"critic"、"critic2" 和 "critic_opt"；评论员的调用方式是
    critic(obs, action)，给出 (B,)。batch 里有 obs、action、reward (B,)、next_obs 和 not_done（(B,)，
    即 1 - terminated）。half_width 是每个动作维度的 (high - low) / 2；low、high 是动作的范围。
    cfg.target_noise 是 sigma，cfg.noise_clip 是 c，单位都是 half_width。公式见上；噪声用
    torch.randn_like(action) 抽。
    """
    obs, action, reward, next_obs, not_done = batch
    with torch.no_grad():  # targets are constants: no gradient flows into them
        # Your code here (你的代码写在这里): eps, the target action, then y.
        raise NotImplementedError("not written yet")
    # L = mean (y - Q1(s, a))^2 + mean (y - Q2(s, a))^2, one y for both (the script's own lines)
    critic_loss = (F.mse_loss(nets["critic"](obs, action), y)
                   + F.mse_loss(nets["critic2"](obs, action), y))
    nets["critic_opt"].zero_grad()
    critic_loss.backward()
    nets["critic_opt"].step()
    return critic_loss.detach()
