"""The exercises and their checker (exercises/check.py): every blank says "not written yet",
the scripts' own functions pass every stage, and typical wrong answers each fail at the
earliest stage that can see them, with a message that names what differs."""

import sys
import textwrap

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "exercises"))
import check  # noqa: E402
import checking  # noqa: E402
from cases import gae as gae_cases  # noqa: E402

HEADER = """
import numpy as np
import math
import torch
import torch.nn.functional as F
from torch.distributions import Categorical, kl_divergence
"""

def dqn_answer(lines):
    """dqn_target's function with `lines` where the blank is (next_max and next_double from
    q_next = Q'(s', .)), then the script's own y and lines."""
    target = textwrap.indent(textwrap.dedent("            " + lines), " " * 8)
    return ("def dqn_update(q_net, q_target, optimizer, batch, cfg):\n"
            "    obs, action, reward, next_obs, not_done = batch\n"
            "    with torch.no_grad():\n"
            "        q_next = q_target(next_obs)\n" + target + "\n"
            "        y = reward + cfg.gamma * not_done * (\n"
            "            next_double if cfg.double else next_max)\n"
            "    q = q_net(obs).gather(-1, action[:, None]).squeeze(-1)\n"
            "    loss = F.smooth_l1_loss(q, y)\n"
            "    optimizer.zero_grad()\n"
            "    loss.backward()\n"
            "    optimizer.step()\n"
            "    return torch.stack([loss.detach(), q.detach().mean(), next_max.mean(),\n"
            "                        next_double.mean()])\n",)


def sac_answer(log_slope="torch.log(actor.scale) + 2 * (math.log(2) - u - F.softplus(-2 * u))",
               q_at="action", logp_at="u", critics="torch.min", loss="(alpha * logp - q).mean()",
               draw="u_dist.rsample()", reduce="sum"):
    """sac_actor_loss's function, the script's lines but for the one named."""
    return f"""def compute_loss_actor(actor, critic, critic2, obs, alpha):
                u_dist = actor.distribution(obs)
                u = {draw}
                action = actor.bias + actor.scale * torch.tanh(u)
                log_slope = {log_slope}
                logp = (u_dist.log_prob({logp_at}) - log_slope).{reduce}(-1)
                q = {critics}(critic(obs, {q_at}), critic2(obs, {q_at}))
                return {loss}, logp"""


# name: [(wrong answer, the stage that must catch it, words its message must hold)]
WRONG = {
    "discounted_returns": [
        ("""def discounted_returns(rewards, next_values, terminated, truncated, gamma):
                returns, future = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
                for t in reversed(range(len(rewards))):  # no bootstrap at the cut
                    future = torch.where(truncated[t], next_values[t], future)
                    future = torch.where(terminated[t], 0.0, future)
                    returns[t] = future = rewards[t] + gamma * future
                return returns""", "(a)", "no bootstrap at the rollout's end"),
        ("""def discounted_returns(rewards, next_values, terminated, truncated, gamma):
                returns, future = torch.zeros_like(rewards), next_values[-1]
                for t in reversed(range(len(rewards))):  # a truncation as a termination
                    future = torch.where(terminated[t] | truncated[t], 0.0, future)
                    returns[t] = future = rewards[t] + gamma * future
                return returns""", "(a)", "truncation treated as a termination"),
        ("""def discounted_returns(rewards, next_values, terminated, truncated, gamma):
                returns, future = torch.zeros_like(rewards), next_values[-1]
                for t in reversed(range(len(rewards))):  # truncation checked last: it wins
                    future = torch.where(terminated[t], 0.0, future)
                    future = torch.where(truncated[t], next_values[t], future)
                    returns[t] = future = rewards[t] + gamma * future
                return returns""", "(a)", "truncation wins where both flags are set"),
        ("""def discounted_returns(rewards, next_values, terminated, truncated, gamma):
                returns, future = torch.zeros_like(rewards), next_values[-1]
                for t in reversed(range(len(rewards))):  # the value one step off at a time limit
                    future = torch.where(truncated[t], next_values[t - 1], future)
                    future = torch.where(terminated[t], 0.0, future)
                    returns[t] = future = rewards[t] + gamma * future
                return returns""", "(a)", "next_values[t - 1]"),
        ("""def discounted_returns(rewards, next_values, terminated, truncated, gamma):
                returns, future = torch.zeros_like(rewards), next_values[-1]
                for t in reversed(range(len(rewards))):  # truncated never read
                    future = torch.where(terminated[t], 0.0, future)
                    returns[t] = future = rewards[t] + gamma * future
                return returns""", "(a)", "truncation ignored"),
    ],
    "gae": [
        ("""def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
                adv, last = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
                for t in reversed(range(len(rewards))):  # tutorial 000: no gamma * lam
                    nt = (~terminated[t]).float()
                    nd = (~(terminated[t] | truncated[t])).float()
                    delta = rewards[t] + gamma * next_values[t] * nt - values[t]
                    last = adv[t] = delta + nd * last
                return adv""", "(a)", "gamma * lam left out of the sum"),
        ("""def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
                adv, last = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
                for t in reversed(range(len(rewards))):  # a truncation as a termination
                    done = (terminated[t] | truncated[t]).float()
                    delta = rewards[t] + gamma * next_values[t] * (1 - done) - values[t]
                    last = adv[t] = delta + gamma * lam * (1 - done) * last
                return adv""", "(a)", "truncation treated as a termination in delta"),
        ("""def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
                adv, last = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
                for t in reversed(range(len(rewards))):  # the sum runs on past a truncation
                    nt = (~terminated[t]).float()
                    delta = rewards[t] + gamma * next_values[t] * nt - values[t]
                    last = adv[t] = delta + gamma * lam * nt * last
                return adv""", "(a)", "the sum runs on past a truncation"),
        ("""def gae(rewards, values, next_values, terminated, truncated, gamma, lam):
                adv, last = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
                for t in reversed(range(len(rewards))):  # lam forgotten
                    done = (terminated[t] | truncated[t]).float()
                    delta = rewards[t] + gamma * next_values[t] * (~terminated[t]).float() - values[t]
                    last = adv[t] = delta + gamma * (1 - done) * last
                return adv""", "(a)", "lam left out of the sum"),
    ],
    "clipped_surrogate": [
        ("""def compute_loss_pi(policy, data, clip_coef):
                dist = Categorical(logits=policy(data["obs"]))
                logp = dist.log_prob(data["act"])
                ratio = torch.exp(logp - data["logp"]).detach()  # no gradient reaches pi
                adv = data["adv"]
                loss = -torch.min(ratio * adv, ratio.clamp(1 - clip_coef, 1 + clip_coef) * adv).mean()
                info = dict(approx_kl=((ratio - 1) - (logp - data["logp"])).mean().detach(),
                            clipfrac=((ratio - 1).abs() > clip_coef).float().mean(), ratio=ratio)
                return loss, dist.entropy().mean(), info""", "(a)",
         "this is exactly what this mistake does: no gradient reaches pi"),
        ("""def compute_loss_pi(policy, data, clip_coef):
                dist = Categorical(logits=policy(data["obs"]))
                logp = dist.log_prob(data["act"])
                ratio = torch.exp(logp - data["logp"])
                adv = data["adv"]  # max: the optimistic bound
                loss = -torch.max(ratio * adv, ratio.clamp(1 - clip_coef, 1 + clip_coef) * adv).mean()
                return loss, dist.entropy().mean(), {}""", "(a)", "max where the pessimistic bound takes min"),
        ("""def compute_loss_pi(policy, data, clip_coef):
                dist = Categorical(logits=policy(data["obs"]))
                logp = dist.log_prob(data["act"])
                ratio = torch.exp(logp - data["logp"])  # the product clipped, not the ratio
                loss = -(ratio * data["adv"]).clamp(1 - clip_coef, 1 + clip_coef).mean()
                return loss, dist.entropy().mean(), {}""", "(a)", "the product r * A clipped"),
        ("""def compute_loss_pi(policy, data, clip_coef):
                dist = Categorical(logits=policy(data["obs"]))
                ratio = torch.exp(dist.log_prob(data["act"]) - data["logp"])
                adv = data["adv"]  # the product clipped inside the min
                loss = -torch.min(ratio * adv, (ratio * adv).clamp(1 - clip_coef, 1 + clip_coef)).mean()
                return loss, dist.entropy().mean(), {}""", "(a)", "clipped inside the min"),
        ("""def compute_loss_pi(policy, data, clip_coef):
                dist = Categorical(logits=policy(data["obs"]))
                ratio = torch.exp(dist.log_prob(data["act"]) - data["logp"])
                adv = data["adv"]  # clipped from above only
                loss = -torch.min(ratio * adv, ratio.clamp(max=1 + clip_coef) * adv).mean()
                return loss, dist.entropy().mean(), {}""", "(a)", "clipped from above only"),
    ],
    "kl_penalty": [
        ("""def compute_loss_pi(policy, data, beta):
                dist = Categorical(logits=policy(data["obs"]))
                ratio = torch.exp(dist.log_prob(data["act"]) - data["logp"])
                kl = kl_divergence(dist, Categorical(logits=data["logits_old"])).mean()  # reversed
                return -(ratio * data["adv"]).mean() + beta * kl, dist.entropy().mean(), dict(kl=kl.detach())
             """, "(a)", "the KL the other way round"),
        ("""def compute_loss_pi(policy, data, beta):
                dist = Categorical(logits=policy(data["obs"]))
                ratio = torch.exp(dist.log_prob(data["act"]) - data["logp"])
                kl = kl_divergence(Categorical(logits=data["logits_old"]), dist).mean().detach()
                return -(ratio * data["adv"]).mean() + beta * kl, dist.entropy().mean(), dict(kl=kl)
             """, "(a)", "wrong gradient"),
        ("""def compute_loss_pi(policy, data, beta):
                dist = Categorical(logits=policy(data["obs"]))
                ratio = torch.exp(dist.log_prob(data["act"]) - data["logp"])
                kl = kl_divergence(Categorical(logits=data["logits_old"]), dist).mean()
                return (ratio * data["adv"]).mean() + beta * kl, dist.entropy().mean(), dict(kl=kl.detach())
             """, "(a)", "the surrogate's sign"),
    ],
    "adapt_beta": [
        ("""def adapt_beta(beta, d, cfg):  # halves where it should double
                if d < cfg.d_targ / cfg.kl_tolerance:
                    return beta * cfg.beta_factor
                if d > cfg.d_targ * cfg.kl_tolerance:
                    return beta / cfg.beta_factor
                return beta""", "(a)", "the two rules swapped"),
        ("""def adapt_beta(beta, d, cfg):  # <= where the paper has <
                if d <= cfg.d_targ / cfg.kl_tolerance:
                    return beta / cfg.beta_factor
                if d > cfg.d_targ * cfg.kl_tolerance:
                    return beta * cfg.beta_factor
                return beta""", "(a)", "<= at the band's lower edge"),
        ("""def adapt_beta(beta, d, cfg):  # no band: against d_targ itself (was named as <=)
                if d < cfg.d_targ:
                    return beta / cfg.beta_factor
                if d > cfg.d_targ:
                    return beta * cfg.beta_factor
                return beta""", "(a)", "no band: d compared with d_targ itself"),
        ("""def adapt_beta(beta, d, cfg):  # the tolerance as the factor
                if d < cfg.d_targ / cfg.kl_tolerance:
                    return beta / cfg.kl_tolerance
                if d > cfg.d_targ * cfg.kl_tolerance:
                    return beta * cfg.kl_tolerance
                return beta""", "(a)", "the tolerance (cfg.kl_tolerance, 1.5 in the paper)"),
    ],
    "a2c_loss": [
        ("""def a2c_loss(model, data, cfg):
                logits, values = model(data["obs"])
                dist = Categorical(logits=logits)
                adv = data["ret"] - values  # A recomputed: its gradient reaches the critic
                loss_pi = -(dist.log_prob(data["act"]) * adv).mean()
                loss_v = 0.5 * ((values - data["ret"]) ** 2).mean()
                entropy = dist.entropy().mean()
                loss = loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * entropy
                return loss, dict(loss_pi=loss_pi.item(), loss_v=loss_v.item(), entropy=entropy.item(),
                                  explained_var=0.0, values=values.detach(), ret=data["ret"])""",
         "(a)", "A recomputed as R - V"),
        ("""def a2c_loss(model, data, cfg):
                logits, values = model(data["obs"])
                dist = Categorical(logits=logits)
                loss_pi = -(dist.log_prob(data["act"]) * data["adv"]).mean()
                loss_v = 0.5 * ((values - data["ret"]) ** 2).mean()
                entropy = dist.entropy().mean()  # the bonus with the wrong sign
                loss = loss_pi + cfg.vf_coef * loss_v + cfg.ent_coef * entropy
                return loss, dict(loss_pi=loss_pi.item(), loss_v=loss_v.item(), entropy=entropy.item())""",
         "(a)", "the entropy bonus with the wrong sign"),
        ("""def a2c_loss(model, data, cfg):
                logits, values = model(data["obs"])
                dist = Categorical(logits=logits)
                loss_pi = -(dist.log_prob(data["act"]) * data["adv"]).mean()
                loss_v = ((values - data["ret"]) ** 2).mean()  # the half forgotten
                entropy = dist.entropy().mean()
                loss = loss_pi + cfg.vf_coef * loss_v - cfg.ent_coef * entropy
                return loss, dict(loss_pi=loss_pi.item(), loss_v=loss_v.item(), entropy=entropy.item())""",
         "(a)", "the critic's loss not halved"),
    ],
    "td_target": [
        ("""def td_target(reward, not_done, next_q, gamma):
                return reward + gamma * next_q  # a future after a termination""", "(a)",
         "no not_done: a future added after a termination"),
        ("""def td_target(reward, not_done, next_q, gamma):
                return reward + gamma * (1 - not_done) * next_q""", "(a)", "(1 - not_done)"),
        ("""def td_target(reward, not_done, next_q, gamma):
                return (reward + gamma * not_done * next_q).unsqueeze(-1)  # (B, 1)""", "(a)",
         "expected shape (3,), got (3, 1)"),
    ],
    "actor_loss": [
        ("""def compute_loss_actor(actor, critic, obs):
                return -critic(obs, actor(obs).detach()).mean()  # no gradient reaches mu""",
         "(a)", "gradient cut"),
        ("""def compute_loss_actor(actor, critic, obs):
                return critic(obs, actor(obs)).mean()  # descends Q""", "(a)", "+Q: the actor must ascend Q"),
        ("""def compute_loss_actor(actor, critic, obs):
                return -critic(obs, actor(obs)).sum()""", "(a)", "a sum over the batch"),
    ],
    "td3_target": [
        ("""def update_critics(nets, batch, half_width, low, high, cfg):
                obs, action, reward, next_obs, not_done = batch
                with torch.no_grad():
                    eps = (torch.randn_like(action) * cfg.target_noise).clamp(-cfg.noise_clip, cfg.noise_clip)
                    a2 = (nets["actor_target"](next_obs) + half_width * eps).clamp(low, high)
                    q1, q2 = nets["critic"](next_obs, a2), nets["critic2"](next_obs, a2)  # not Q'
                    y = reward + cfg.gamma * not_done * torch.min(q1, q2)
                critic_loss = (F.mse_loss(nets["critic"](obs, action), y)
                               + F.mse_loss(nets["critic2"](obs, action), y))
                nets["critic_opt"].zero_grad()
                critic_loss.backward()
                nets["critic_opt"].step()
                return critic_loss.detach()""", "(a)", "the critics being trained"),
        ("""def update_critics(nets, batch, half_width, low, high, cfg):
                obs, action, reward, next_obs, not_done = batch
                with torch.no_grad():
                    eps = (torch.randn_like(action) * cfg.target_noise).clamp(-cfg.noise_clip, cfg.noise_clip)
                    a2 = (nets["actor"](next_obs) + half_width * eps).clamp(low, high)  # not mu'
                    q1, q2 = nets["critic_target"](next_obs, a2), nets["critic2_target"](next_obs, a2)
                    y = reward + cfg.gamma * not_done * torch.min(q1, q2)
                critic_loss = (F.mse_loss(nets["critic"](obs, action), y)
                               + F.mse_loss(nets["critic2"](obs, action), y))
                nets["critic_opt"].zero_grad()
                critic_loss.backward()
                nets["critic_opt"].step()
                return critic_loss.detach()""", "(a)", "the actor being trained"),
        ("""def update_critics(nets, batch, half_width, low, high, cfg):
                obs, action, reward, next_obs, not_done = batch
                with torch.no_grad():
                    eps = (torch.randn_like(action) * cfg.target_noise).clamp(-cfg.noise_clip, cfg.noise_clip)
                    a2 = (nets['actor_target'](next_obs) + half_width * eps).clamp(low, high)
                    q1, q2 = nets["critic_target"](next_obs, a2), nets["critic2_target"](next_obs, a2)
                    y = reward + cfg.gamma * not_done * torch.max(q1, q2)
                critic_loss = (F.mse_loss(nets["critic"](obs, action), y)
                               + F.mse_loss(nets["critic2"](obs, action), y))
                nets["critic_opt"].zero_grad()
                critic_loss.backward()
                nets["critic_opt"].step()
                return critic_loss.detach()""", "(a)", "max where clipped double Q takes the smaller"),
        ("""def update_critics(nets, batch, half_width, low, high, cfg):
                obs, action, reward, next_obs, not_done = batch
                with torch.no_grad():
                    eps = torch.randn_like(action) * cfg.target_noise  # not clipped
                    a2 = (nets['actor_target'](next_obs) + half_width * eps).clamp(low, high)
                    q1, q2 = nets["critic_target"](next_obs, a2), nets["critic2_target"](next_obs, a2)
                    y = reward + cfg.gamma * not_done * torch.min(q1, q2)
                critic_loss = (F.mse_loss(nets["critic"](obs, action), y)
                               + F.mse_loss(nets["critic2"](obs, action), y))
                nets["critic_opt"].zero_grad()
                critic_loss.backward()
                nets["critic_opt"].step()
                return critic_loss.detach()""", "(a)", "the noise not clipped to [-c, c]"),
        ("""def update_critics(nets, batch, half_width, low, high, cfg):
                obs, action, reward, next_obs, not_done = batch
                with torch.no_grad():
                    eps = (torch.randn_like(action) * cfg.target_noise).clamp(-cfg.noise_clip, cfg.noise_clip)
                    a2 = nets['actor_target'](next_obs) + half_width * eps  # not in the box
                    q1, q2 = nets["critic_target"](next_obs, a2), nets["critic2_target"](next_obs, a2)
                    y = reward + cfg.gamma * not_done * torch.min(q1, q2)
                critic_loss = (F.mse_loss(nets["critic"](obs, action), y)
                               + F.mse_loss(nets["critic2"](obs, action), y))
                nets["critic_opt"].zero_grad()
                critic_loss.backward()
                nets["critic_opt"].step()
                return critic_loss.detach()""", "(a)", "a~ not clipped into the action box"),
    ],
    "group_advantages": [
        ("""def group_advantages(rewards, G, scale):
                r = rewards.view(-1, G)  # the std without Bessel's correction
                adv = r - r.mean(1, keepdim=True)
                return (adv / (r.std(1, keepdim=True, unbiased=False) + 1e-4) if scale else adv).reshape(-1)""",
         "(a)", "without Bessel's correction"),
        ("""def group_advantages(rewards, G, scale):
                adv = rewards - rewards.mean()  # the whole batch as one group
                return adv / (rewards.std() + 1e-4) if scale else adv""", "(a)",
         "over the whole batch"),
        ("""def group_advantages(rewards, G, scale):
                r = rewards.view(G, -1)  # groups down the columns
                adv = r - r.mean(0, keepdim=True)
                return (adv / (r.std(0, keepdim=True) + 1e-4) if scale else adv).reshape(-1)""",
         "(a)", "the groups read down the columns"),
    ],
    "grpo_loss": [
        ("""def grpo_loss(logp, logp_old, logp_ref, adv, mask, cfg):
                ratio = torch.exp(logp - logp_old)
                s = torch.min(ratio * adv[:, None],
                              ratio.clamp(1 - cfg.clip_coef, 1 + cfg.clip_coef) * adv[:, None])
                x = logp - logp_ref  # pi / pi_ref
                kl = torch.exp(x) - x - 1
                per_token = (s - cfg.beta * kl) * mask
                length = mask.sum(1) if cfg.length_norm else torch.full_like(mask[:, 0], mask.shape[1])
                loss = -(per_token.sum(1) / length).mean()
                return loss, dict(kl=0.0, clipfrac=0.0, ratio=ratio.detach())""", "(a)", "k3 the other way round"),
        ("""def grpo_loss(logp, logp_old, logp_ref, adv, mask, cfg):
                ratio = torch.exp(logp - logp_old)
                s = torch.min(ratio * adv[:, None],
                              ratio.clamp(1 - cfg.clip_coef, 1 + cfg.clip_coef) * adv[:, None])
                x = logp_ref - logp
                kl = torch.exp(x) - x - 1
                per_token = (s - cfg.beta * kl)  # no mask
                length = mask.sum(1) if cfg.length_norm else torch.full_like(mask[:, 0], mask.shape[1])
                loss = -(per_token.sum(1) / length).mean()
                return loss, dict(kl=0.0, clipfrac=0.0, ratio=ratio.detach())""", "(a)", "the mask not applied"),
        ("""def grpo_loss(logp, logp_old, logp_ref, adv, mask, cfg):
                ratio = torch.exp(logp - logp_old)
                s = torch.min(ratio * adv[:, None],
                              ratio.clamp(1 - cfg.clip_coef, 1 + cfg.clip_coef) * adv[:, None])
                x = logp_ref - logp
                kl = torch.exp(x) - x - 1
                per_token = (s - cfg.beta * kl) * mask
                length = mask.sum(1) if cfg.length_norm else torch.full_like(mask[:, 0], mask.shape[1])
                loss = -per_token.sum() / mask.sum()  # one mean over tokens
                return loss, dict(kl=0.0, clipfrac=0.0, ratio=ratio.detach())""", "(a)", "one mean over all the batch's tokens"),
    ],
    "a2c_targets": [
        ("""def a2c_targets(model, rollout, next_obs, cfg):
                import common
                _, values = model(rollout["obs"])  # no torch.no_grad()
                _, last = model(torch.as_tensor(next_obs, dtype=torch.float32))
                next_values = torch.cat([values[1:], last[None]])
                if cfg.lam is None:
                    returns = common.discounted_returns(rollout["rewards"], next_values,
                                                        rollout["terminated"], rollout["truncated"], cfg.gamma)
                    return returns, returns - values
                advantages = common.gae(rollout["rewards"], values, next_values, rollout["terminated"],
                                        rollout["truncated"], cfg.gamma, cfg.lam)
                return advantages + values, advantages""", "(a)", "carry a gradient into the critic"),
        ("""def a2c_targets(model, rollout, next_obs, cfg):
                import common
                with torch.no_grad():
                    _, values = model(rollout["obs"])
                    next_values = values  # not shifted
                if cfg.lam is None:
                    returns = common.discounted_returns(rollout["rewards"], next_values,
                                                        rollout["terminated"], rollout["truncated"], cfg.gamma)
                    return returns, returns - values
                advantages = common.gae(rollout["rewards"], values, next_values, rollout["terminated"],
                                        rollout["truncated"], cfg.gamma, cfg.lam)
                return advantages + values, advantages""", "(a)", "next_values = values"),
        ("""def a2c_targets(model, rollout, next_obs, cfg):
                import common
                with torch.no_grad():
                    _, values = model(rollout["obs"])
                    next_values = torch.cat([values[1:], torch.zeros_like(values[:1])])  # no bootstrap
                if cfg.lam is None:
                    returns = common.discounted_returns(rollout["rewards"], next_values,
                                                        rollout["terminated"], rollout["truncated"], cfg.gamma)
                    return returns, returns - values
                advantages = common.gae(rollout["rewards"], values, next_values, rollout["terminated"],
                                        rollout["truncated"], cfg.gamma, cfg.lam)
                return advantages + values, advantages""", "(a)", "no bootstrap at the rollout's end"),
    ],
    "ddpg_update": [
        ("""def ddpg_update(actor, critic, actor_target, critic_target, actor_opt, critic_opt, batch, cfg):
                from ddpg_walker import compute_loss_actor, soft_update, td_target
                obs, action, reward, next_obs, not_done = batch
                with torch.no_grad():  # both networks being trained in the target
                    y = td_target(reward, not_done, critic(next_obs, actor(next_obs)), cfg.gamma)
                critic_loss = F.mse_loss(critic(obs, action), y)
                critic_opt.zero_grad()
                critic_loss.backward()
                critic_opt.step()
                actor_loss = compute_loss_actor(actor, critic, obs)
                actor_opt.zero_grad()
                actor_loss.backward(inputs=list(actor.parameters()))
                actor_opt.step()
                soft_update(critic_target, critic, cfg.tau)
                soft_update(actor_target, actor, cfg.tau)
                return critic_loss.detach(), actor_loss.detach()""", "(a)", "the target from the networks being trained"),
        ("""def ddpg_update(actor, critic, actor_target, critic_target, actor_opt, critic_opt, batch, cfg):
                from ddpg_walker import compute_loss_actor, soft_update, td_target
                obs, action, reward, next_obs, not_done = batch
                with torch.no_grad():
                    y = td_target(reward, not_done, critic_target(next_obs, actor_target(next_obs)), cfg.gamma)
                actor_loss = compute_loss_actor(actor, critic, obs)  # the actor's step first
                actor_opt.zero_grad()
                actor_loss.backward(inputs=list(actor.parameters()))
                actor_opt.step()
                critic_loss = F.mse_loss(critic(obs, action), y)
                critic_opt.zero_grad()
                critic_loss.backward()
                critic_opt.step()
                soft_update(critic_target, critic, cfg.tau)
                soft_update(actor_target, actor, cfg.tau)
                return critic_loss.detach(), actor_loss.detach()""", "(a)", "the actor's step taken before the critic's"),
        ("""def ddpg_update(actor, critic, actor_target, critic_target, actor_opt, critic_opt, batch, cfg):
                from ddpg_walker import compute_loss_actor, soft_update, td_target
                obs, action, reward, next_obs, not_done = batch
                with torch.no_grad():
                    y = td_target(reward, not_done, critic(next_obs, actor_target(next_obs)), cfg.gamma)
                critic_loss = F.mse_loss(critic(obs, action), y)
                critic_opt.zero_grad()
                critic_loss.backward()
                critic_opt.step()
                actor_loss = compute_loss_actor(actor, critic, obs)
                actor_opt.zero_grad()
                actor_loss.backward(inputs=list(actor.parameters()))
                actor_opt.step()
                soft_update(critic_target, critic, cfg.tau)
                soft_update(actor_target, actor, cfg.tau)
                return critic_loss.detach(), actor_loss.detach()""", "(a)", "the target from the critic being trained"),
        ("""def ddpg_update(actor, critic, actor_target, critic_target, actor_opt, critic_opt, batch, cfg):
                from ddpg_walker import compute_loss_actor, soft_update, td_target
                obs, action, reward, next_obs, not_done = batch
                y = td_target(reward, not_done, critic_target(next_obs, actor_target(next_obs)), cfg.gamma)
                critic_loss = F.mse_loss(critic(obs, action), y)
                critic_opt.zero_grad()
                critic_loss.backward()
                critic_opt.step()
                actor_loss = compute_loss_actor(actor, critic, obs)
                actor_opt.zero_grad()
                actor_loss.backward(inputs=list(actor.parameters()))
                actor_opt.step()
                soft_update(critic_target, critic, cfg.tau)
                soft_update(actor_target, actor, cfg.tau)
                return critic_loss.detach(), actor_loss.detach()""", "(a)", "a gradient reached critic_target"),
        ("""def ddpg_update(actor, critic, actor_target, critic_target, actor_opt, critic_opt, batch, cfg):
                from ddpg_walker import compute_loss_actor, soft_update, td_target
                obs, action, reward, next_obs, not_done = batch
                with torch.no_grad():
                    y = td_target(reward, not_done, critic_target(next_obs, actor_target(next_obs)), cfg.gamma)
                critic_loss = F.mse_loss(critic(obs, action), y)
                critic_opt.zero_grad()
                critic_loss.backward()
                critic_opt.step()
                actor_loss = compute_loss_actor(actor, critic, obs)
                actor_opt.zero_grad()
                actor_loss.backward(inputs=list(actor.parameters()))
                actor_opt.step()
                soft_update(critic_target, critic, cfg.tau)
                # the actor's target forgotten
                return critic_loss.detach(), actor_loss.detach()""", "(a)", "the actor's target after the soft update"),
        ("""def ddpg_update(actor, critic, actor_target, critic_target, actor_opt, critic_opt, batch, cfg):
                from ddpg_walker import compute_loss_actor, soft_update, td_target
                obs, action, reward, next_obs, not_done = batch
                with torch.no_grad():
                    y = td_target(reward, not_done, critic_target(next_obs, actor_target(next_obs)), cfg.gamma)
                critic_loss = F.mse_loss(critic(obs, action), y)
                critic_loss.backward()
                critic_opt.step()
                critic_opt.zero_grad()  # zeroed after the step, not before the backward
                actor_loss = compute_loss_actor(actor, critic, obs)
                actor_loss.backward()  # no inputs=: the critic's .grad keeps this till its next step
                actor_opt.step()
                actor_opt.zero_grad()
                soft_update(critic_target, critic, cfg.tau)
                soft_update(actor_target, actor, cfg.tau)
                return critic_loss.detach(), actor_loss.detach()""", "(a)",
         "left the actor's gradient in the critic's .grad"),
    ],
    "ddpg_store_step": [
        ("""def store_and_advance(env, buffer, obs, action, reward, next_obs, terminated, truncated):
                buffer.add(obs, action, reward, next_obs, terminated or truncated)  # done
                if terminated or truncated:
                    next_obs, _ = env.reset()
                return next_obs""", "(a)", "terminated or truncated stored as the episode's end"),
        ("""def store_and_advance(env, buffer, obs, action, reward, next_obs, terminated, truncated):
                buffer.add(obs, action, reward, next_obs, truncated)  # the wrong flag
                if terminated or truncated:
                    next_obs, _ = env.reset()
                return next_obs""", "(a)", "the termination not stored"),
        ("""def store_and_advance(env, buffer, obs, action, reward, next_obs, terminated, truncated):
                buffer.add(next_obs, action, reward, obs, terminated)  # s and s' swapped
                if terminated or truncated:
                    next_obs, _ = env.reset()
                return next_obs""", "(a)", "obs and next_obs swapped"),
        ("""def store_and_advance(env, buffer, obs, action, reward, next_obs, terminated, truncated):
                buffer.add(obs, action, reward, next_obs, terminated)
                if terminated or truncated:
                    obs, _ = env.reset()
                return obs  # not advanced when the episode goes on""", "(a)", "obs not advanced"),
        ("""def store_and_advance(env, buffer, obs, action, reward, next_obs, terminated, truncated):
                buffer.add(obs, action, reward, next_obs, terminated)
                if terminated:  # a truncated episode goes on
                    next_obs, _ = env.reset()
                return next_obs""", "(a)", "no new episode after a time-limit truncation"),
        ("""def store_and_advance(env, buffer, obs, action, reward, next_obs, terminated, truncated):
                if terminated or truncated:  # reset first
                    next_obs, _ = env.reset()
                buffer.add(obs, action, reward, next_obs, terminated)
                return next_obs""", "(a)", "the new episode's first obs stored as s'"),
        ("""def store_and_advance(env, buffer, obs, action, reward, next_obs, terminated, truncated):
                buffer.add(obs, action, reward, next_obs, terminated)
                if terminated or truncated:
                    next_obs = env.reset()  # gym's old API
                return next_obs""", "(a)", "env.reset() returns (obs, info)"),
        ("""def store_and_advance(env, buffer, obs, action, reward, next_obs, terminated, truncated):
                buffer.add(obs, action, reward, next_obs, not terminated)  # not_done passed in
                if terminated or truncated:
                    next_obs, _ = env.reset()
                return next_obs""", "(a)", "the flag the other way round"),
    ],
    "ppo_rollout_step": [
        ("""def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                                  autoreset):
                done = terminated | truncated  # one done flag, as tutorial 000 has
                buffer.store(t, obs, action, reward, done, truncated, valid=~autoreset)
                return next_obs, done""", "(a)", "terminated or truncated stored as terminated"),
        ("""def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                                  autoreset):
                buffer.store(t, obs, action, reward, truncated, terminated, valid=~autoreset)
                return next_obs, terminated | truncated""", "(a)", "the termination stored as a time-limit truncation"),
        ("""def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                                  autoreset):
                buffer.store(t, obs, action, reward, np.zeros_like(terminated), truncated,
                             valid=~autoreset)  # terminated forgotten
                return next_obs, terminated | truncated""", "(a)", "a termination not stored as one"),
        ("""def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                                  autoreset):
                buffer.store(t, obs, action, reward, terminated, truncated, valid=np.ones_like(autoreset))
                return next_obs, terminated | truncated""", "(a)", "the autoreset step not masked"),
        ("""def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                                  autoreset):
                done = terminated | truncated
                buffer.store(t, obs, action, reward, terminated, truncated, valid=~done)
                return next_obs, done""", "(a)", "the step that ended the episode masked"),
        ("""def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                                  autoreset):
                buffer.store(t, next_obs, action, reward, terminated, truncated, valid=~autoreset)
                return next_obs, terminated | truncated""", "(a)", "next_obs stored as obs"),
        ("""def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                                  autoreset):
                buffer.store(t, obs, action, reward, terminated, truncated, valid=~autoreset)
                return next_obs, terminated  # only a fallen pole resets""", "(a)", "the mask from terminated alone"),
        ("""def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                                  autoreset):
                buffer.store(t, obs, action, reward, terminated, truncated, valid=~autoreset)
                return obs, terminated | truncated""", "(a)", "obs not advanced"),
        ("""def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                                  autoreset):
                buffer.store(t, obs, action, reward, terminated, truncated, valid=autoreset)
                return next_obs, terminated | truncated""", "(a)", "valid = autoreset"),
        ("""def store_and_advance(buffer, t, obs, action, reward, next_obs, terminated, truncated,
                                  autoreset):
                buffer.store(t, obs, action, reward, terminated, truncated, valid=~autoreset)
                return next_obs, autoreset | terminated | truncated  # the mask kept""", "(a)",
         "the mask kept from the steps before"),
    ],
    "soft_update": [
        ("""def soft_update(target, source, tau):
                with torch.no_grad():
                    for pt, p in zip(target.parameters(), source.parameters()):
                        pt.mul_(tau).add_((1 - tau) * p)  # tau on the wrong side""", "(a)",
         "tau and 1 - tau swapped"),
        ("""def soft_update(target, source, tau):
                target.load_state_dict(source.state_dict())  # a hard copy""", "(a)", "expected 0.1"),
        ("""def soft_update(target, source, tau):
                with torch.no_grad():
                    for pt, p in zip(target.parameters(), source.parameters()):
                        pt = tau * p + (1 - tau) * pt  # a new tensor; the target stays""", "(a)",
         "expected 0.1"),
    ],
    "dqn_target": [dqn_answer(lines) + (stage, needle) for lines, stage, needle in [
        ("""next_max = q_net(next_obs).max(-1).values  # the online net's max
            a_star = q_net(next_obs).argmax(-1, keepdim=True)
            next_double = q_next.gather(-1, a_star).squeeze(-1)""",
         "(a)", "max_a Q(s', a) of the network being trained"),
        ("""next_max = q_next.max(-1).values  # Double: the target picks, the online net values
            a_star = q_next.argmax(-1, keepdim=True)
            next_double = q_net(next_obs).gather(-1, a_star).squeeze(-1)""",
         "(a)", "Double DQN the other way round"),
        ("""next_max = q_next.max(-1).values
            a_star = q_net(next_obs).argmax(-1, keepdim=True)
            next_double = q_next.gather(-1, a_star).squeeze(-1)
            not_done = torch.ones_like(reward)  # bootstraps at a termination""",
         "(a)", "a future after a termination"),
        ("""next_max = q_next.max(-1).values
            a_star = q_net(next_obs).argmax(-1, keepdim=True)
            next_double = q_next.gather(-1, a_star).squeeze(-1)
            cfg = type(cfg)(**{**vars(cfg), "double": False})  # --double ignored""",
         "(a)", "DQN's target, where --double asks for Double DQN's"),
        ("""next_max = q_next.max(-1).values
            next_double = q_next.gather(-1, q_net(next_obs).argmax(-1, keepdim=True))  # (B, 1)""",
         "(a)", "y broadcasts to (B, B)"),
        ("""next_max = q_next.max(-1).values
            a_star = q_net(next_obs).argmax(-1, keepdim=True)
            next_double = q_next.gather(-1, a_star).squeeze(-1)
            not_done = 1 - not_done  # as if it were terminated""",
         "(a)", "not_done is already 1 - terminated"),
    ]],
    "sac_actor_loss": [(sac_answer(**lines), stage, needle) for lines, stage, needle in [
        (dict(draw="u_dist.loc + u_dist.scale * torch.randn_like(u_dist.loc)  # its own eps"),
         "(a)", "your answer drew its own noise"),
        (dict(log_slope="torch.zeros_like(u)  # no correction"), "(a)", "no tanh correction"),
        (dict(log_slope="-(torch.log(actor.scale) + 2 * (math.log(2) - u - F.softplus(-2 * u)))"),
         "(a)", "the correction's sign flipped"),
        (dict(log_slope="torch.log(actor.scale * (1 - torch.tanh(u) ** 2))  # log(0) in the tail"),
         "(a)", "log(1 - tanh(u)^2) computed directly"),
        (dict(log_slope="torch.log(actor.scale * (1 - torch.tanh(u) ** 2 + 1e-6))"), "(a)",
         "the epsilon keeps it finite"),
        (dict(log_slope="2 * (math.log(2) - u - F.softplus(-2 * u))  # scale left out"), "(a)",
         "scale left out of the correction"),
        (dict(q_at="u"), "(a)", "the pre-squash sample u"),
        (dict(logp_at="action"), "(a)", "log density taken at the squashed action"),
        (dict(critics="torch.max"), "(a)", "max(Q1, Q2) where SAC takes the smaller"),
        (dict(loss="(-alpha * logp - q).mean()"), "(a)", "the entropy term's sign"),
        (dict(draw="u_dist.sample()"), "(a)", "sample(), not rsample()"),
        (dict(loss="(alpha * logp.detach() - q).mean()"), "(a)", "log pi detached in the loss"),
        (dict(reduce="mean"), "(a)", "averaged over the action's dimensions"),
    ]],
}



def script_with(name, old, new):
    """The script's own function for exercise `name`, with the line part `old` replaced."""
    import inspect
    ex = check.EXERCISES[name]
    source = inspect.getsource(getattr(ex.owner(), ex.function))
    assert source.count(old) == 1, old
    return f"from {ex.owner().__name__} import *\n" + source.replace(old, new)


SOFT = """def soft_update(target, source, tau):
                with torch.no_grad():
                    for pt, p in zip(target.parameters(), source.parameters()):
                        {}"""
GROUP = """def group_advantages(rewards, G, scale):
                r = rewards.view(-1, G)
                adv = r - r.mean(1{keep})
                return (adv / {den} if scale else adv).reshape(-1)"""
TD3_TWO_DRAWS = """def update_critics(nets, batch, half_width, low, high, cfg):
                obs, action, reward, next_obs, not_done = batch
                with torch.no_grad():
                    mu = nets["actor_target"](next_obs)
                    def smoothed():  # a fresh draw at each call: one per critic
                        eps = (torch.randn_like(action) * cfg.target_noise).clamp(-cfg.noise_clip, cfg.noise_clip)
                        return (mu + half_width * eps).clamp(low, high)
                    q = torch.min(nets["critic_target"](next_obs, smoothed()),
                                  nets["critic2_target"](next_obs, smoothed()))
                    y = reward + cfg.gamma * not_done * q
                critic_loss = (F.mse_loss(nets["critic"](obs, action), y)
                               + F.mse_loss(nets["critic2"](obs, action), y))
                nets["critic_opt"].zero_grad()
                critic_loss.backward()
                nets["critic_opt"].step()
                return critic_loss.detach()"""
WRONG["soft_update"] += [
    (SOFT.format("pt = tau * p + (1 - tau) * pt  # rebinds a name"), "(a)",
     "the target did not move: assign in place"),
    (SOFT.format("p.mul_(1 - tau).add_(tau * pt)  # moves the source"), "(a)",
     "the target did not move"),
    (SOFT.format("pt.copy_(p)"), "(a)", "a hard copy: tau = 1"),
    (SOFT.format("pt.add_(tau * p).mul_(1 - tau)"), "(a)", "the two steps in the wrong order")]
WRONG["grpo_loss"] += [
    (script_with("grpo_loss", "per_token = (surrogate - cfg.beta * kl) * mask",
                 "per_token = surrogate * mask - cfg.beta * kl"), "(a)",
     "the KL term not masked: padding tokens pay a KL"),
    (script_with("grpo_loss", "length = mask.sum(1) if cfg.length_norm else",
                 "length = mask.sum(1) if True else"), "(a)", "length_norm ignored"),
    (script_with("grpo_loss", "kl = torch.exp(log_ref_ratio) - log_ref_ratio - 1",
                 "kl = -log_ref_ratio"), "(a)", "k1, log(pi / pi_ref), where this loss uses k3"),
    (script_with("grpo_loss", "loss = -(per_token.sum(1) / length).mean()",
                 "loss = -per_token.mean()"), "(a)", "one mean over all (B, L) entries")]
WRONG["actor_loss"] += [
    ("""def compute_loss_actor(actor, critic, obs):
                with torch.no_grad():
                    a = actor(obs)
                return -critic(obs, a).mean()""", "(a)",
     "the action computed without a gradient: torch.no_grad() or .detach()")]
WRONG["td3_target"] += [(TD3_TWO_DRAWS, "(a)", "two noise draws, one per critic")]
WRONG["group_advantages"] += [
    (GROUP.format(keep=", keepdim=True", den="r.std(1, keepdim=True).clamp_min(1e-4)"), "(a)",
     "the 1e-4 as a floor (std.clamp_min(1e-4))"),
    (GROUP.format(keep=", keepdim=True", den="(r.std(1, keepdim=True) + 1e-8)"), "(a)",
     "1e-8 added where this project adds 1e-4"),
    (GROUP.format(keep=", keepdim=True", den="r.std(1, keepdim=True)"), "(a)",
     "the 1e-4 left out"),
    (GROUP.format(keep="", den="(r.std(1) + 1e-4)"), "(a)", "mean/std without keepdim=True"),
    ("""def group_advantages(rewards, G, scale):
                return rewards.float()  # raw rewards: (a)'s first case tells, (b) must too""",
     "(a)", "expected 1.4997")]
WRONG["clipped_surrogate"] += [
    (script_with("clipped_surrogate", "loss_pi = -torch.min(ratio * adv, clip_adv).mean()",
                 "loss_pi = -(torch.min(ratio, torch.clamp(ratio, 1 - clip_coef, 1 + clip_coef)) * adv).mean()"),
     "(a)", "the min taken over the ratios")]
WRONG["grpo_loss"] += [  # the right value, the wrong gradient: no mistake's value may name it
    (script_with("grpo_loss", "kl = torch.exp(log_ref_ratio) - log_ref_ratio - 1",
                 "kl = (torch.exp(log_ref_ratio) - log_ref_ratio - 1).detach()"), "(a)",
     "wrong gradient: the value is right")]
WRONG["kl_penalty"] += [
    (script_with("kl_penalty", 'dist).mean()', 'dist).sum()'), "(a)",
     "the KL summed over the batch (.sum())")]
WRONG["td_target"] += [
    ("""def td_target(reward, not_done, next_q, gamma):
                return (reward + gamma * next_q) * not_done""", "(a)",
     "(r + gamma * Q') * not_done: the reward itself zeroed")]
WRONG["ddpg_update"] += [
    (script_with("ddpg_update", "    critic_opt.zero_grad()\n", ""), "(a)",
     "gradients accumulated across updates: critic_opt.zero_grad() missing"),
    (script_with("ddpg_update", "    actor_opt.zero_grad()\n", ""), "(a)",
     "gradients accumulated across updates: actor_opt.zero_grad() missing"),
    (script_with("ddpg_update", "return critic_loss.detach(), actor_loss.detach()",
                 "return critic_loss, actor_loss"), "(a)", "the losses returned with their graph")]

RTG = """def reward_to_go(rewards, gamma, last_value=0.0):
                {}"""
WRONG["reward_to_go"] = [
    (script_with("reward_to_go", "return returns", "return np.full(len(rewards), G)  # G_0"),
     "(a)", "the whole episode's return G_0 for every step"),
    (script_with("reward_to_go", "for t in reversed(range(len(rewards))):",
                 "for t in range(len(rewards)):"), "(a)", "the sum run forward"),
    (RTG.format("return np.cumsum([gamma ** k * r for k, r in enumerate(rewards)])"), "(a)",
     "a running sum from the episode's start"),
    (RTG.format("return np.array([sum(gamma ** k * rewards[k] for k in range(t, len(rewards))) "
                "for t in range(len(rewards))])"), "(a)",
     "gamma^k counted from the episode's start"),
    (script_with("reward_to_go", "G = rewards[t] + gamma * G", "G = gamma * (rewards[t] + G)"),
     "(a)", "the reward itself discounted"),
    (script_with("reward_to_go", "G = rewards[t] + gamma * G", "G = rewards[t] + G"), "(a)",
     "gamma left out"),
    (script_with("reward_to_go", "np.zeros(len(rewards)), last_value",
                 "np.zeros(len(rewards)), 0.0"), "(a)", "last_value ignored"),
    (script_with("reward_to_go", "returns, G = np.zeros(len(rewards)), last_value",
                 "rewards = list(rewards[:-1]) + [rewards[-1] + last_value]  # a last reward\n"
                 "    returns, G = np.zeros(len(rewards)), 0.0"), "(a)",
     "last_value not discounted"),
    (RTG.format("""returns, G = [], last_value
                for t in reversed(range(len(rewards))):
                    G = rewards[t] + gamma * G
                    returns.append(G)  # never turned round
                return np.array(returns)"""), "(a)", "the returns in reverse order"),
]
WRONG["reinforce_loss"] = [(script_with("reinforce_loss", old, new), "(a)", needle)
                           for old, new, needle in [
    ("loss_pi = -(", "loss_pi = (", "the sign: +mean(log pi * weights)"),
    ("* weights).mean()", "* weights).sum()",
     "a sum over the batch (.sum()) where the script takes the mean (.mean()): the step then "
     "grows with the batch's length"),
    ("ret - values.detach() if", "ret + values.detach() if", "the baseline added, G + V"),
    ("ret - values.detach() if", "values.detach() - ret if", "the weight the other way round"),
    ("weights = ret - values.detach() if baseline else ret", "weights = ret",
     "baseline ignored: the weights are G_t alone where baseline = True"),
    ("weights = ret - values.detach() if baseline else ret", "weights = ret - values.detach()",
     "baseline ignored: G_t - V(s_t) where baseline = False"),
    ("weights = ret - values.detach() if baseline else ret",
     "weights = ret - values.detach() if baseline else ret\n"
     "    weights = (weights - weights.mean()) / (weights.std() + 1e-8)", "the weights normalized"),
    ("log_prob(act)", "log_prob(act).exp()", "pi(a|s) where log pi(a|s) belongs"),
    ("loss_v = 0.5 * (", "loss_v = (", "the baseline's loss not halved"),
    ("** 2).mean()", "** 2).sum()", "the baseline's loss summed"),
    ("ret - values.detach() if", "ret - values if",
     "loss_pi: a gradient where none belongs: the value is right, and your loss sends a gradient "
     "into V(s)"),
    ("ret - values.detach() if", "ret - values if", "V(s_t) not detached in the weight"),
    ("((values - ret)", "((values.detach() - ret)", "V(s_t) detached in loss_v too"),
    ("policy(obs)", "policy(obs).detach()", "log pi(a|s) computed without a gradient"),
]]


def td_answer(sarsa, value=None, delta="{target} - Q[s, a]", step="Q[s, a] += alpha * td_error",
              back="float(td_error)", cut="(1 - terminated)", discount="gamma * "):
    """sarsa_update's or q_learning_update's function, written out: the target r + gamma *
    (1 - terminated) * value, its TD error, the step and the return, each replaceable."""
    value = value or ("Q[s_next, a_next]" if sarsa else "Q[s_next].max()")
    target = f"(r + {discount}{cut} * {value})" if cut else f"(r + {discount}{value})"
    head = ("def sarsa_update(Q, s, a, r, s_next, a_next, terminated, alpha, gamma):" if sarsa
            else "def q_learning_update(Q, s, a, r, s_next, terminated, alpha, gamma):")
    return f"""{head}
                td_error = {delta.format(target=target)}
                {step}
                return {back}"""


TD_MISTAKES = [  # (the part written otherwise, the words the message must hold): both exercises
    (dict(cut=""), "a bootstrap at a termination"),
    (dict(cut="(~terminated)"), "~terminated on a Python bool"),
    (dict(discount=""), "gamma left out"),
    (dict(step="Q[s, a] = r + gamma * (1 - terminated) * VALUE"),
     "alpha left out: Q[s, a] = target, a full replacement"),
    (dict(delta="Q[s, a] - {target}"), "the TD error's sign: delta = Q[s, a] - target"),
    (dict(back="-float(td_error)"), "the TD error returned with its sign flipped"),
    (dict(back="float(r + gamma * (1 - terminated) * VALUE - Q[s, a])"),
     "the TD error computed after the update"),
    (dict(back="float(alpha * td_error)"), "the step alpha * delta returned"),
    (dict(step="Q[s_next, 0] += alpha * td_error"), "the entry of s' updated"),
    (dict(step="Q = Q.copy(); Q[s, a] += alpha * td_error"),
     "not the caller's: update it in place"),
    (dict(back="None"), "nothing returned: return delta"),
]


def td_wrong(sarsa):
    own = "Q[s_next, a_next]" if sarsa else "Q[s_next].max()"
    return [(td_answer(sarsa, **{k: v.replace("VALUE", own) for k, v in parts.items()}), "(a)",
             needle) for parts, needle in TD_MISTAKES]


WRONG["sarsa_update"] = td_wrong(True) + [
    (td_answer(True, value="Q[s_next].max()"), "(a)",
     "max_a' Q(s', a') where Sarsa takes the next action a' (that is Q-learning's target"),
    (td_answer(True, value="Q[s_next, a]"), "(a)", "Q(s', a), the action just taken, where Sarsa "
     "takes the next action a_next"),
]
WRONG["q_learning_update"] = td_wrong(False) + [
    (td_answer(False, value="Q[s_next, a]"), "(a)", "Q(s', a), the action just taken valued at "
     "s', where Q-learning takes the best action there"),
    (td_answer(False, value="Q[s_next].mean()"), "(a)", "the mean over the actions of s'"),
    (td_answer(False, value="np.argmax(Q[s_next])"), "(a)", "argmax (an action's index) where "
     "the max (its value) belongs"),
    (td_answer(False, value="Q[s].max()"), "(a)", "the max at s, not at s'"),
    (td_answer(False, value="Q.max()"), "(a)", "the max over the whole table"),
]

# Named mistakes: a setting written as a number (the script's default or a usual one), a sum
# where the mean belongs, a std over the wrong axis, gamma and lambda swapped, and the like
EXACTLY = "this is exactly what this mistake gives: "

WRONG["discounted_returns"] += [
    ("""def discounted_returns(rewards, next_values, terminated, truncated, gamma):
            returns, future = torch.zeros_like(rewards), next_values[-1]
            for t in reversed(range(len(rewards))):
                future = torch.where(terminated[t], 0.0, torch.where(truncated[t],
                                                                     next_values[t], future))
                returns[t] = future = rewards[t] + 0.99 * future
            return returns""", "(a)", EXACTLY + "0.99 written as a number where gamma is meant")]
WRONG["discounted_returns"] += [
    ("""def discounted_returns(rewards, next_values, terminated, truncated, gamma):
            future = next_values[-1]
            for t in reversed(range(len(rewards))):
                future = torch.where(terminated[t], 0.0, torch.where(truncated[t],
                                                                     next_values[t], future))
                rewards[t] = future = rewards[t] + gamma * future
            return rewards""", "(a)",
     "this is exactly what this mistake does: a result written into an input")]
WRONG["discounted_returns"] += [
    ("""def discounted_returns(rewards, next_values, terminated, truncated, gamma):
            returns, future, T = torch.zeros_like(rewards), next_values[-1], len(rewards)
            for t in reversed(range(T)):
                future = torch.where(truncated[t], next_values[t], future)
                if t + 1 < T:
                    future = torch.where(terminated[t + 1], torch.zeros_like(future), future)
                returns[t] = future = rewards[t] + gamma * future
            return returns""", "(a)", EXACTLY + "terminated[t + 1] read at step t")]
WRONG["a2c_loss"] += [(script_with("a2c_loss", old, new), "(a)", EXACTLY + needle)
                      for old, new, needle in (
    ("cfg.vf_coef", "0.5", "0.5 written as a number where cfg.vf_coef is meant"),
    ("-(dist.log_prob(act) * adv).mean()", "-(dist.log_prob(act) * adv).sum()",
     "loss_pi summed over the batch"),
    ("dist.entropy().mean()", "dist.entropy().sum()", "the entropy summed over the batch"))]
WRONG["sarsa_update"] += [(td_answer(True).replace("alpha *", "0.5 *"), "(a)",
                           EXACTLY + "0.5, the script's default, written as a number where alpha")]
WRONG["q_learning_update"] += [(td_answer(False).replace("Q[s, a] +=", "Q[s] +="), "(a)",
                                EXACTLY + "the whole row Q[s] moved")]
WRONG["td_target"] += [("""def td_target(reward, not_done, next_q, gamma):
                              return gamma * (reward + not_done * next_q)""", "(a)",
                        EXACTLY + "gamma on the reward too")]
WRONG["gae"] += [(script_with("gae", "gamma * next_values[t]", "lam * next_values[t]").replace(
    "gamma * lam * not_done[t] * last", "gamma * not_done[t] * last"), "(a)",
    EXACTLY + "gamma and lambda swapped")]
GAE_CUT_LATE = script_with(  # done_{t+1} cuts A_t's sum
    "gae", "last = advantages[t] = delta + gamma * lam * not_done[t] * last",
    "last = advantages[t] = delta + gamma * lam * last\n        last = last * not_done[t]")
WRONG["gae"] += [(script_with("gae", "not_done[t] * last", "last"), "(a)",
                  EXACTLY + "the sum is not cut where an episode ended"),
                 (GAE_CUT_LATE, "(a)", "expected 0, got 0.5")]


def test_a_sum_cut_a_step_late_is_not_named_as_a_sum_never_cut():
    """On two steps the two give the same numbers; the three-step case with a termination in
    the middle tells them apart, so the late cut gets no name rather than the wrong one."""
    passed, lines = run("gae", compile_answer(GAE_CUT_LATE, "gae"))
    assert not passed and EXACTLY not in "\n".join(lines), lines
WRONG["group_advantages"] += [("""def group_advantages(rewards, G, scale):
        r = rewards.view(-1, G)
        adv = r - r.mean(1, keepdim=True)
        if scale:
            adv = adv / (r.std(0, keepdim=True) + 1e-4)
        return adv.reshape(-1)""", "(a)", EXACTLY + "the std over axis 0")]
WRONG["bradley_terry_loss"] = [(f"""def bradley_terry_loss(r_chosen, r_rejected):
        return {body}""", "(a)", EXACTLY + needle) for body, needle in (
    ("-torch.log(torch.sigmoid(r_chosen - r_rejected)).mean()", "torch.log(torch.sigmoid(gap))"),
    ("-F.logsigmoid((r_chosen - r_rejected).mean())", "the mean gap inside the log"))]
WRONG["reward_to_go"] += [(script_with("reward_to_go", old, new), "(a)", needle)
                          for old, new, needle in (
    ("np.zeros(len(rewards))", "np.zeros_like(rewards)", "an integer array: it truncates every G_t"),
    ("returns, G = np.zeros(len(rewards)), last_value", "returns, G = np.zeros(len(rewards)), "
     "gamma * last_value", EXACTLY + "G started at gamma * last_value"))]


ADAPT_BETA = """def adapt_beta(beta, d, cfg):
        if d < cfg.d_targ / cfg.kl_tolerance:
            return beta / cfg.beta_factor
        if d > cfg.d_targ * cfg.kl_tolerance:
            return beta * cfg.beta_factor
        return beta"""
WRONG["adapt_beta"] += [(ADAPT_BETA.replace(old, new), "(a)", EXACTLY + needle)
                        for old, new, needle in (
    ("return beta / cfg.beta_factor", "return beta", "beta never lowered"),)]
WRONG["adapt_beta"] += [(ADAPT_BETA.replace("beta / cfg", "beta - cfg").replace(
    "beta * cfg", "beta + cfg"), "(a)", EXACTLY + "beta moved by adding and subtracting")]
WRONG["adapt_beta"] += [(ADAPT_BETA.replace("kl_tolerance", "TOL").replace(
    "beta_factor", "kl_tolerance").replace("TOL", "beta_factor"), "(a)",
    EXACTLY + "cfg.kl_tolerance and cfg.beta_factor swapped")]
WRONG["kl_penalty"] += [(script_with("kl_penalty", "ratio = torch.exp(logp - logp_old)",
                                     "ratio = logp - logp_old"), "(a)",
                         EXACTLY + "the ratio without exp")]
WRONG.setdefault("gaussian_log_prob", []).append(("""def gaussian_log_prob(mu, log_std, act):
        z = (act - mu) / log_std.exp()
        return (-0.5 * z ** 2 - log_std - 0.5 * math.log(2 * math.pi)).sum(0)""", "(a)",
    EXACTLY + "summed over the batch (.sum(0), axis 0)"))
WRONG["a2c_targets"] += [(script_with(  # the last step wraps round to V(s_0)
    "a2c_targets", "torch.cat([values[1:], last_value[None]])", "torch.roll(values, -1, 0)"),
    "(a)", EXACTLY + "values rolled (torch.roll(values, -1, 0))")]
WRONG["gae"] += [(script_with("gae", "    return advantages", "    return advantages + values"),
                  "(a)", EXACTLY + "the value targets A_t + V(s_t) returned")]
WRONG["gaussian_log_prob"].append((script_with(  # log(2 pi) per dimension, not its half
    "gaussian_log_prob", "0.5 * np.log(2 * np.pi)", "np.log(2 * np.pi)"), "(a)",
    EXACTLY + "log(2 pi) where each dimension's constant is log(2 pi) / 2"))


@pytest.fixture(autouse=True)
def english():
    """The messages in English whatever the locale (the checker's default follows it)."""
    checking.LANG = "en"
    yield
    checking.LANG = "en"


def compile_answer(source, name):
    namespace = {}
    exec(HEADER + textwrap.dedent(source), namespace)
    return namespace[check.EXERCISES[name].function]


def run(name, fn, learning=False):
    lines = []
    passed = check.check(name, fn=fn, learning=learning, say=lines.append)
    return passed, lines


BLANKS = [name for name in check.EXERCISES if name not in check.BUGS]


BLANK = 'raise NotImplementedError("not written yet")'


def blank_as_shipped(name):
    """Skip where the learner has filled in exercises/<name>.py: the shipped blank is what is
    tested, and an answer of one's own (right or wrong) must never fail the test suite."""
    if BLANK not in (check.HERE / f"{name}.py").read_text():
        pytest.skip(f"exercises/{name}.py is filled in (its blank is tested in a fresh clone)")


@pytest.mark.quick
@pytest.mark.parametrize("name", BLANKS)
def test_each_blank_says_not_written_yet(name):
    blank_as_shipped(name)
    passed, lines = run(name, None)
    assert not passed and lines == [f"{name}: (a) worked cases: FAIL: not written yet (fill in "
                                    f"the blank in exercises/{name}.py)"]


@pytest.mark.quick
def test_a_filled_in_exercise_is_skipped_not_failed(tmp_path, monkeypatch):
    monkeypatch.setattr(check, "HERE", tmp_path)
    (tmp_path / "gae.py").write_text("def gae(*args):\n    return 0  # an answer, right or wrong\n")
    with pytest.raises(pytest.skip.Exception):
        blank_as_shipped("gae")


@pytest.mark.parametrize("name", BLANKS)
def test_the_scripts_own_function_passes_the_cases_and_the_loop(name):
    ex = check.EXERCISES[name]
    passed, lines = run(name, getattr(ex.owner(), ex.function))
    assert passed, lines


@pytest.mark.parametrize("name,index", [(name, i) for name in WRONG for i in range(len(WRONG[name]))])
def test_a_wrong_answer_fails_at_the_earliest_stage_that_sees_it(name, index):
    source, stage, needle = WRONG[name][index]
    passed, lines = run(name, compile_answer(source, name))
    assert not passed and lines[-1].startswith(f"{name}: {stage}"), lines
    assert needle in lines[-1], lines[-1]


def bug_as_shipped(bug):
    """The planted bug's function, or a skip where the learner has fixed it."""
    passed, lines = run(bug, check.load(bug))
    if passed:
        pytest.skip(f"exercises/{bug}.py is fixed (its bug is tested in a fresh clone)")
    return lines


@pytest.mark.quick
@pytest.mark.parametrize("bug", check.BUGS)
def test_each_planted_bug_fails_and_the_table_does_not_give_it_away(bug, capsys):
    lines = bug_as_shipped(bug)
    assert "FAIL" in lines[-1]
    with pytest.raises(SystemExit) as exit:
        check.main(["--lang", "en"])
    assert exit.value.code == 1  # a blank or a bug left: not everything passed
    (row,) = [line for line in capsys.readouterr().out.splitlines() if line.startswith(bug)]
    assert row.split() == [bug, "not", "fixed", "yet"]


@pytest.mark.quick
def test_the_table_exits_0_only_when_every_exercise_passes(monkeypatch, capsys):
    """Every exercise answered with the script's own function: status 0; one left as it is
    (the shipped blank): status 1, whatever the learner's other files hold."""
    own = {name: getattr(ex.owner(), ex.function) for name, ex in check.EXERCISES.items()}
    monkeypatch.setattr(check, "real_loop", lambda ex, fn: None)  # (a) is enough to tell here
    monkeypatch.setattr(check, "load", lambda name: own[name])
    with pytest.raises(SystemExit) as exit:
        check.main(["--lang", "en"])
    assert exit.value.code == 0, capsys.readouterr().out
    monkeypatch.setattr(check, "load", lambda name: own[name] if name != "gae" else blank)
    with pytest.raises(SystemExit) as exit:
        check.main(["--lang", "en"])
    assert exit.value.code == 1 and "gae" in capsys.readouterr().out


def blank(*args):
    raise NotImplementedError("not written yet")


NO_INPUTS = """def ddpg_update(actor, critic, actor_target, critic_target, actor_opt, critic_opt, batch, cfg):
    from ddpg_walker import compute_loss_actor, soft_update, td_target
    obs, action, reward, next_obs, not_done = batch
    with torch.no_grad():
        y = td_target(reward, not_done, critic_target(next_obs, actor_target(next_obs)), cfg.gamma)
    critic_loss = F.mse_loss(critic(obs, action), y)
    critic_opt.zero_grad()
    critic_loss.backward()
    critic_opt.step()
    actor_loss = compute_loss_actor(actor, critic, obs)
    actor_opt.zero_grad()
    actor_loss.backward()  # no inputs=: the critic's .grad is filled too, and zeroed before its use
    actor_opt.step()
    soft_update(critic_target, critic, cfg.tau)
    soft_update(actor_target, actor, cfg.tau)
    return critic_loss.detach(), actor_loss.detach()"""


def test_a_harmless_difference_passes_the_worked_cases():
    """The actor's backward without inputs= fills the critic's .grad as well, and the critic's
    next step zeroes it before its own backward: the same numbers, so (a) passes it (its twin
    that zeroes the critic after the step fails: WRONG["ddpg_update"])."""
    check.worked_cases(check.EXERCISES["ddpg_update"], compile_answer(NO_INPUTS, "ddpg_update"))


def test_a_loop_that_no_longer_calls_the_function_fails_loudly():
    """If the script's settings or code stop calling the exercise's function (A2C with GAE
    instead of the n-step returns), stage (b) says so instead of passing any answer."""
    ex = check.EXERCISES["discounted_returns"]
    loop = dict(ex.loop, lam=0.95, total_timesteps=512)  # one update (8 envs x 64 steps)
    moved = check.SimpleNamespace(**{**vars(ex), "loop": loop})
    with pytest.raises(check.Failed, match="never called discounted_returns"):
        check.real_loop(moved, lambda *args: None)


@pytest.mark.quick
def test_messages_in_chinese(monkeypatch, capsys):
    """In Chinese every line is Chinese, punctuated as Chinese is (full-width colons), the
    table's lines included."""
    monkeypatch.setattr(checking, "LANG", "zh")
    passed, lines = run("td_target", compile_answer(WRONG["td_target"][0][0], "td_target"))
    assert not passed and lines[-1].startswith(
        "td_target：第 (a) 关“手算的例子”未通过：例子：r = (1, 2, 3)"), lines
    assert "第一个不同在下标 (1,)" in lines[-1]
    monkeypatch.setattr(check, "real_loop", lambda ex, fn: None)  # (a) is enough to tell here
    ex = check.EXERCISES["td_target"]
    passed, lines = run("td_target", getattr(ex.owner(), ex.function))
    assert passed and lines[0].startswith("td_target：第 (a) 关“手算的例子”通过（") \
        and lines[0].endswith(" 秒）"), lines
    passed, lines = run("td_target", compile_answer("def td_target(*args):\n    return 1 / 0",
                                                    "td_target"))
    line = HEADER.count("\n") + 2  # the answer's second line, after the imports
    assert lines == ["td_target：第 (a) 关“手算的例子”未通过：你的代码抛出了 "
                     f"ZeroDivisionError（<string> 第 {line} 行）：division by zero"], lines
    own = {name: getattr(ex.owner(), ex.function) for name, ex in check.EXERCISES.items()}
    monkeypatch.setattr(check, "load", lambda name: own[name] if name != "gae" else blank)
    with pytest.raises(SystemExit):
        check.main(["--lang", "zh"])
    table = capsys.readouterr().out.splitlines()
    assert table[0].split() == ["discounted_returns", "第", "(a)、(b)", "关都通过"], table
    assert table[1].split(maxsplit=1) == [
        "gae", "第 (a) 关“手算的例子”未通过：还没写（在 exercises/gae.py 里填空）"], table
    for text in lines + table:
        assert ": " not in text and "FAIL" not in text and "pass" not in text, text


@pytest.mark.quick
def test_no_learning_says_stage_c_was_not_run_and_help_follows_the_language(monkeypatch, capsys):
    """All passes under --no-learning end with a line that (c) did not run, and how to run it;
    --help in Chinese has a Chinese line under each option, and a known mistake stands on a
    line of its own after the sentence that introduces it."""
    ex = check.EXERCISES["td_target"]
    monkeypatch.setattr(check, "real_loop", lambda ex, fn: None)
    monkeypatch.setattr(check, "load", lambda name: getattr(ex.owner(), ex.function))
    for lang, words in (("zh", "第 (c) 关“学会任务”没有跑"), ("en", "(c) learning: not run")):
        with pytest.raises(SystemExit) as exit:
            check.main(["td_target", "--no-learning", "--lang", lang])
        last = capsys.readouterr().out.splitlines()[-1]
        assert exit.value.code == 0 and words in last and "check.py td_target" in last, last
    with pytest.raises(SystemExit):
        check.main(["--help", "--lang", "zh"])
    out = capsys.readouterr().out
    assert "只跑第 (a)、(b) 两关" in out and "检查练习，分三关" in out, out
    assert "显示本帮助并退出" in out and "LANG 等以 zh 开头就用" in out and "跟随" not in out, out
    with pytest.raises(SystemExit):  # --help-zh, as the scripts take it
        check.main(["--help-zh"])
    assert capsys.readouterr().out == out
    monkeypatch.setattr(checking, "LANG", "zh")
    passed, lines = run("td_target", compile_answer(WRONG["td_target"][0][0], "td_target"))
    assert "常见错误会得到的值：\n    没有乘 not_done，" in lines[-1], lines[-1]


@pytest.mark.slow
@pytest.mark.parametrize("name", ["gae", "kl_penalty", "a2c_loss", "td_target", "td3_target",
                                  "reinforce_loss", "sarsa_update", "q_learning_update"])
def test_the_scripts_own_functions_learn(name):
    """Stage (c) with the scripts' own functions: one exercise per script (the others of the
    same script run the very same training). These are the CartPole scripts', DDPG's and
    TD3's learning tests (seed 0; TD3's seed 2, 25,000 steps: exercises/check.py's TD3_LEARN);
    DQN's and SAC's are in their scripts' tests. REINFORCE's is its defaults' run, cut at
    150,000 steps; CliffWalking's has one exercise per agent, each with its own bar."""
    ex = check.EXERCISES[name]
    result = check.learns(ex, getattr(ex.owner(), ex.function))  # raises check.Failed if not
    if "eval_returns" in result:  # CartPole: solved (learns checks it), from short episodes,
        assert np.mean(result["episode_returns"][:20]) < 100  # and pi holds the pole when tested
        assert np.mean(result["eval_returns"]) >= 450
    if ex.script in ("ddpg_walker", "td3_walker", "sac_walker"):  # from falling to balancing
        assert result["evaluations"][0]["eval_mean"] < 200  # (DDPG's seeds 0-4: experiments.md)
        assert [e["eval_mean"] for e in result["evaluations"][-check.HOLD:]] == [1000] * check.HOLD


def test_the_cliff_bars_tell_sarsa_from_q_learning():
    """Stage (c) on CliffWalking (under a second each): Sarsa written with Q-learning's max
    walks the cliff's edge, and fails Sarsa's bar (the safe path); Q-learning written with the
    mean over s' (expected Sarsa under a uniform policy) misses Q-learning's (the optimal
    path, its Q there Q*)."""
    for name, source, words in (
            ("sarsa_update", td_answer(True, value="Q[s_next].max()"), "is not the safe one"),
            ("q_learning_update", td_answer(False, value="Q[s_next].mean()"),
             "its greedy path is not the optimal one")):
        with pytest.raises(check.Failed, match=words):
            check.learns(check.EXERCISES[name], compile_answer(source, name))


@pytest.mark.slow
@pytest.mark.parametrize("bug", check.BUGS)
def test_each_planted_bug_fails_its_learning_stage(bug):
    """Stage (c) with the planted bug: it must fail where the bug harms learning (DDPG's
    bug_td_target balances the pole for a while and loses it again: one evaluation at 1000
    is not enough)."""
    bug_as_shipped(bug)
    with pytest.raises(check.Failed) as failed:
        check.learns(check.EXERCISES[bug], check.load(bug))
    assert "not solved" in str(failed.value) or "not all 1000" in str(failed.value)


def test_the_checker_from_the_command_line(tmp_path, capsys):
    import os

    from conftest import run_script

    if BLANK not in (check.HERE / "td_target.py").read_text():
        pytest.skip("exercises/td_target.py is filled in")
    p = run_script("exercises/check.py", "td_target", "--lang", "en", timeout=120)
    assert p.returncode == 1 and "not written yet" in p.stdout, p.stdout + p.stderr
    p = run_script("exercises/check.py", "td_target", timeout=120,
                   env=dict(os.environ, LC_ALL="", LC_MESSAGES="", LANG="zh_CN.UTF-8"))
    assert p.returncode == 1 and "还没写" in p.stdout, p.stdout + p.stderr
    with pytest.raises(SystemExit) as stop:  # the same main(), in this process
        check.main(["nope"])
    assert stop.value.code == 2 and "invalid choice" in capsys.readouterr().err


@pytest.mark.parametrize("answer", ["raw rewards", "whole batch", "loss times 0"])
def test_grpo_stage_b_tells_answers_apart(answer):
    """Stage (b)'s GRPO run has groups with mixed rewards (one-digit sums after 60 supervised
    steps), so advantages and the KL are not all 0 there: answers that (b) once passed whatever
    they were (rewards as advantages, one mean and std for the batch, a loss of 0) fail it."""
    import grpo_addition
    own_loss = grpo_addition.grpo_loss
    fn, name = dict(
        [("raw rewards", (lambda rewards, G, scale: rewards.float(), "group_advantages")),
         ("whole batch", (lambda rewards, G, scale: (rewards - rewards.mean())
                          / (rewards.std() + 1e-4), "group_advantages")),
         ("loss times 0", (lambda *args: (own_loss(*args)[0] * 0, own_loss(*args)[1]),
                           "grpo_loss"))])[answer]
    with pytest.raises(check.Failed, match="the logs first differ at update"):
        check.real_loop(check.EXERCISES[name], fn)


@pytest.mark.quick
def test_grpo_stage_b_refuses_a_run_whose_groups_are_all_flat(monkeypatch):
    """If the loop's settings ever give every group equal rewards again, (b) says it is the
    checker's fault instead of passing every answer (the reference logs faked here)."""
    ex = check.EXERCISES["grpo_loss"]
    key = (ex.script, tuple(sorted(ex.loop.items())))
    monkeypatch.setitem(check.REFERENCE, key, [dict(flat_groups="", loss="1.0"),
                                               dict(flat_groups="1", loss="-0")])
    with pytest.raises(check.Failed, match="every group's rewards are equal"):
        check.real_loop(ex, lambda *args: None)
    monkeypatch.setitem(check.REFERENCE, key, [dict(flat_groups="0.5", loss="-0.0025")])
    monkeypatch.setattr(check, "loop_logs", lambda ex, fn, tmp: fn() or [
        dict(flat_groups="0.5", loss="-0.0025")])
    check.real_loop(ex, lambda *args: None)  # mixed groups: the stage runs, and passes here


@pytest.mark.quick
def test_stage_b_passes_a_rounding_only_difference_with_a_note(monkeypatch):
    """The logs are compared exactly; where the first difference is in the last digits only
    (relative < 1e-5), (b) passes with a note that it is probably only the order of float
    operations; a larger first difference still fails."""
    ex = check.EXERCISES["soft_update"]
    key = (ex.script, tuple(sorted(ex.loop.items())))
    reference = [dict(step="301", critic_loss="0.5", actor_loss="-1"),
                 dict(step="302", critic_loss="0.623107", actor_loss="-1")]
    monkeypatch.setitem(check.REFERENCE, key, reference)
    for yours, passes in (("0.623106", True), ("0.623", False)):
        rows = [dict(reference[0]), dict(reference[1], critic_loss=yours, actor_loss="-7")]
        monkeypatch.setattr(check, "loop_logs", lambda ex, fn, tmp: fn() or rows)
        if passes:
            note = check.real_loop(ex, lambda *args: None)
            assert "step 302, in critic_loss, by rounding only (0.623107 vs 0.623106)" in note
            assert "probably only the order of float operations" in note
        else:
            with pytest.raises(check.Failed, match="script's own gives 0.623107, yours 0.623"):
                check.real_loop(ex, lambda *args: None)


def test_a_soft_update_right_in_value_passes_stage_b():
    """p_target.lerp_(p, tau) is the soft update in another order of float operations: its
    logs differ from step 302 on in the last digit; (b) passes it, saying why."""
    passed, lines = run("soft_update", compile_answer(SOFT.format("pt.lerp_(p, tau)"),
                                                      "soft_update"))
    assert passed and "by rounding only" in lines[-1], lines


@pytest.mark.quick
def test_the_loop_notes_name_the_exercise_and_the_gae_message_fits_the_loops():
    """soft_update's (b) note says what its function moved, not that another function may be
    to blame; gae's values[t + 1] mistake says the two coincide in this project's loops."""
    hint = check.EXERCISES["soft_update"].loop_hint()
    assert "moved by your function" in hint and "another function" not in hint
    r, v = checking.t([1.0, 1.0], [1.0, 1.0]), checking.t([1.0, 1.0], [2.0, 2.0])
    labels = [label for label, _ in gae_cases.mistakes(
        r, v, v, checking.flags([False, False], [False, False]),
        checking.flags([True, True], [False, False]), 0.5, 1.0)]
    assert any("they coincide with values[t + 1] in this project's" in x for x in labels), labels
    assert not any("is the next episode's first state, not" in x for x in labels), labels


def test_a_mistake_that_gives_the_right_value_names_nothing():
    """A wrong gradient with the right value (the k3 term detached) is not named after a
    mistake whose value, in that case, is the right one (length_norm ignored, where
    length_norm = True)."""
    source = WRONG["grpo_loss"][-1][0]
    passed, lines = run("grpo_loss", compile_answer(source, "grpo_loss"))
    assert not passed and "wrong gradient" in lines[-1], lines
    assert "this is exactly what this mistake" not in lines[-1], lines[-1]


PLAIN = [name for name, ex in check.EXERCISES.items()
         if not ex.worked_cases and ex.mistakes and name not in check.BUGS]


@pytest.mark.quick
@pytest.mark.parametrize("name", PLAIN)
def test_every_listed_mistake_is_wrong_on_every_case_that_computes_it(name):
    """Where a case cannot tell a listed mistake from the right answer, the mistake says so
    (checking.only_if gives None there); nowhere else may it give the right answer."""
    ex = check.EXERCISES[name]
    checking.audit(ex, ex.cases())


@pytest.mark.quick
def test_a_case_on_which_a_listed_mistake_is_right_is_refused():
    """A mistake that gives the right answer on a case, unmarked, stops stage (a) with a line
    for the maintainer, whatever the answer."""
    ex = check.EXERCISES["td_target"]
    right = ex.cases()[0][2]
    broken = check.SimpleNamespace(**{**vars(ex), "mistakes": lambda *args: [("planted", right)]})
    with pytest.raises(checking.CheckerFault, match='mistake "planted" gives the right answer'):
        checking.check_cases(broken, getattr(ex.owner(), ex.function))
    passed, lines = run("td_target", getattr(ex.owner(), ex.function))
    assert passed, lines


TWO_SLIPS = """def discounted_returns(rewards, next_values, terminated, truncated, gamma):
                returns, future = torch.zeros_like(rewards), torch.zeros_like(rewards[0])
                for t in reversed(range(len(rewards))):  # no bootstrap, a truncation as an end
                    future = torch.where(terminated[t] | truncated[t], 0.0, future)
                    returns[t] = future = rewards[t] + gamma * future
                return returns"""


@pytest.mark.quick
def test_a_mistake_is_named_only_where_every_case_agrees():
    """Two slips at once give "no bootstrap at the rollout's end"'s value on the first case
    and another on the truncated ones: neither is named (an unnamed mistake is better than a
    misnamed one); the first slip alone is named (WRONG["discounted_returns"])."""
    passed, lines = run("discounted_returns", compile_answer(TWO_SLIPS, "discounted_returns"))
    assert not passed and "no episode ends" in lines[-1], lines
    assert "this is exactly what this mistake" not in lines[-1], lines[-1]


@pytest.mark.quick
def test_a_slip_that_shares_one_number_with_a_mistake_gets_its_own_name_or_none():
    """tau left off the source's term gives 1.0 after the first soft update, as a hard copy
    does, and 1.9 after the second: named for what it is, not a hard copy. An argmax taken at
    s gives DQN's y on this batch's non-terminal rows only where argmax Q(s) = argmax Q'(s'):
    the case keeps them apart, and nothing is named."""
    passed, lines = run("soft_update", compile_answer(SOFT.format("pt.mul_(1 - tau).add_(p)"),
                                                      "soft_update"))
    assert not passed and "tau left off the network's term" in lines[-1], lines
    assert "a hard copy" not in lines[-1], lines[-1]
    passed, lines = run("dqn_target", compile_answer(dqn_answer(
        """next_max = q_next.max(-1).values
            a_star = q_net(obs).argmax(-1, keepdim=True)  # at s, not s'
            next_double = q_next.gather(-1, a_star).squeeze(-1)""")[0], "dqn_target"))
    assert not passed and "Double DQN (cfg.double = True)" in lines[-1], lines
    assert "this is exactly what this mistake" not in lines[-1], lines[-1]
