"""Exercise: log pi(a|s) of a diagonal Gaussian policy, the log-probability PPO needs for
continuous actions (Schulman et al. 2017, the MuJoCo policy of section 6.1).

From ppo_reacher.py: pi(a|s) = N(mu(s), diag(sigma^2)), the network giving mu and a parameter
giving log sigma, one per action dimension. The dimensions are independent, so the density of
the action is the product of the dimensions' densities, and its log the sum of their logs:
    log pi(a|s) = sum_i [-(a_i - mu_i)^2 / (2 sigma_i^2) - log sigma_i - log(2 pi) / 2]
In PPO's ratio exp(log pi - log pi_old) the constant log(2 pi) / 2 cancels; log pi itself
(and the density) needs it.

    python exercises/check.py gaussian_log_prob
The reference answer: ppo_reacher.gaussian_log_prob (ppo_reacher.py).

练习：对角高斯策略的 log π(a|s)，连续动作的 PPO 要用它（Schulman 等 2017，第 6.1 节 MuJoCo 的策略）。
在 ppo_reacher.py 里 π(a|s) = N(mu(s), diag(sigma^2))：网络给出 mu，log sigma 是单独的参数，动作的
每一维一个。各维相互独立，所以动作的密度是各维密度之积，取对数就是各维对数密度之和（公式见上）。
PPO 的比值 exp(log π - log π_old) 里常数 log(2π)/2 会消掉；但 log π 本身（以及密度）需要它。
参考答案：ppo_reacher.gaussian_log_prob。
"""

import math

import torch


def gaussian_log_prob(mu, log_std, act):
    """log pi(a|s) of each action in the batch, (B,).

    mu: (B, act_dim), the means; log_std: (act_dim,), log sigma of each dimension (the same
    for every state); act: (B, act_dim), the actions.

        log pi(a|s) = sum_i [-(a_i - mu_i)^2 / (2 sigma_i^2) - log sigma_i - log(2 pi) / 2]

    A worked example, one action of two dimensions, mu = 0, sigma = 1, a = (1, 0):
    -1/2 - 0 - 0.919 = -1.419 for the first, -0.919 for the second, -2.338 in all.

    批量里每个动作的 log π(a|s)，形状 (B,)。mu 是 (B, act_dim) 的均值；log_std 是 (act_dim,)，
    每一维的 log sigma（所有状态都一样）；act 是 (B, act_dim) 的动作。按上面的公式，对动作的各维
    求和。例子：一个两维的动作，mu = 0，sigma = 1，a = (1, 0)：第一维 -1/2 - 0 - 0.919 = -1.419，
    第二维 -0.919，合计 -2.338。
    """
    # Your code here (你的代码写在这里): sigma from log_std, each dimension's log density,
    # then their sum over the last dimension.
    raise NotImplementedError("not written yet")
