"""TD3+BC (Fujimoto & Gu 2021, "A Minimalist Approach to Offline RL"), batched over skills.

Reads top to bottom like CORL's ``td3_bc.py``: the config, helpers, the networks, and the
trainer whose ``train_step(batch)`` returns a dict of logs; the replay buffer that feeds it
is ``learning.replay``.

Batching: the K skills' actors (and their 2K critics) are stored as stacked weight tensors of
shape ``(K, in, out)`` and evaluated with ``torch.baddbmm``, so one ``train_step`` updates all
K skills at once; a single skill is K = 1. Each skill's loss is its own mean over its own
batch and the optimised loss is the *sum* over skills, so skill k's gradients, Adam state and
weights are exactly those it would get if trained alone.

Randomness: every draw comes from per-skill ``torch.Generator`` objects seeded with that
skill's seed (``skill_seed``): one for its initial weights, one for its batch indices and
smoothing noise. A skill's training therefore does not depend on which skills it is batched
with, and the same seeds give the same weights (on CPU, bit for bit).

Units: the networks see normalised observations (``checkpoints.normalise_observations``:
``(obs - mean) / std`` clipped to ±``OBS_CLIP``) and work in normalised actions in [-1, 1];
a physical action is the actor's tanh output times ``action_scale``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import torch

from osg_control.domain.spaces import ACTION_DIM, OBS_DIM
from osg_control.learning.replay import OBS_NORM_EPS, Batch


@dataclass(frozen=True)
class TD3BCConfig:
    """Hyper-parameters of TD3+BC (defaults: the paper's and CORL's)."""

    hidden_sizes: tuple[int, ...] = (256, 256)  # widths of the ReLU layers of actor and critics
    actor_lr: float = 3e-4  # Adam learning rate of the actor
    critic_lr: float = 3e-4  # Adam learning rate of the twin critics
    batch_size: int = 256  # transitions sampled per skill per update
    gamma: float = 0.99  # discount factor
    tau: float = 0.005  # Polyak rate of the target networks
    policy_noise: float = 0.2  # std of target policy smoothing noise [normalised action]
    noise_clip: float = 0.5  # clip of that noise [normalised action]
    policy_freq: int = 2  # actor and target updates happen every this many critic updates
    # Weight of the RL term; lambda = alpha / mean |Q|. 0.25, not the paper's 2.5: measured
    # here (10 episodes per skill at 2 cm noise, 5k updates), alpha 2.5 and 1.0 let the
    # actor drift in directions the data never covers (e.g. closing the gripper during a
    # movement skill) while 0.25 kept it on the data: 0.0/0.5 -> 1.0/1.0 on two movement
    # skills. See docs/learning.md.
    alpha: float = 0.25
    # Added to the observation std before dividing by it. 1e-2 rather than CORL's 1e-3:
    # features nearly constant in a skill's data (gripper command, grip force, finger gap
    # in movement skills) otherwise turn small deviations into inputs of hundreds of std.
    obs_norm_eps: float = OBS_NORM_EPS
    # Bounds of the TD target. The reward is sparse (1 on a step that reaches beta, and
    # such a step is terminal), so every true return lies in [0, 1]; clipping the
    # bootstrapped target to that range stops the critic from diverging on out-of-data
    # actions (seen here without it: critic loss 1e5 after 15k updates). None disables it.
    target_q_range: tuple[float, float] | None = (0.0, 1.0)
    # Weight of the BC error on the gripper command (the last action component) where the
    # data switches the gripper (|a| > 0.5). Algorithm 1 records one switch per waypoint
    # among hold (0) labels at nearly the same states, so the plain regression settles in
    # the hold band and the skill never closes or opens (seen here: grab-handle stopped at
    # the handle with g = -0.47 in every episode, 0.2 success at sigma = 0). 1 disables it.
    gripper_switch_weight: float = 10.0
    # Std [m] of Gaussian noise added to the TCP position (the observation's first three
    # features) of every sampled observation and next observation, drawn from the skill's
    # own generator (``replay.BatchedReplay``). Algorithm 1 records the true TCP, while at
    # run time the policy reads a noisy or filtered one; with noise in training it learns
    # what to do from readings as uncertain as those. 0 trains on the data as recorded.
    obs_noise: float = 0.0

    def to_json_dict(self) -> dict[str, Any]:
        """The fields as a JSON-ready dict (for checkpoint sidecars)."""
        data = asdict(self)
        data["hidden_sizes"] = list(self.hidden_sizes)
        if self.target_q_range is not None:
            data["target_q_range"] = list(self.target_q_range)
        return data


# ----------------------------------------------------------------------------- helpers


def bc_weights(actions: torch.Tensor, gripper_switch_weight: float) -> torch.Tensor:
    """Per-element weights of the BC error: ``gripper_switch_weight`` on the gripper command
    of transitions that switch the gripper (normalised |a| > 0.5), 1 elsewhere.

    Args:
        actions: (..., action_dim) normalised data actions, gripper command last.
        gripper_switch_weight: see ``TD3BCConfig``.

    Returns:
        Weights broadcastable against ``actions``.
    """
    weights = torch.ones_like(actions)
    switching = actions[..., -1].abs() > 0.5
    weights[..., -1] = torch.where(switching, gripper_switch_weight, 1.0)
    return weights


# ----------------------------------------------------------------------------- replay buffer


def init_mlp(sizes: Sequence[int], generator: torch.Generator) -> list[torch.Tensor]:
    """One MLP's parameters, initialised like ``torch.nn.Linear``.

    Args:
        sizes: layer widths from input to output, e.g. ``(10, 256, 256, 7)``.
        generator: the source of the uniform draws.

    Returns:
        ``[w0, b0, w1, b1, ...]`` with ``w`` (in, out) and ``b`` (1, out), drawn from
        U(-1/sqrt(in), 1/sqrt(in)).
    """
    params = []
    for fan_in, fan_out in zip(sizes[:-1], sizes[1:], strict=True):
        bound = fan_in**-0.5
        for shape in ((fan_in, fan_out), (1, fan_out)):
            params.append((torch.rand(shape, generator=generator) * 2 - 1) * bound)
    return params


def stack_mlps(mlps: Sequence[Sequence[torch.Tensor]], device: torch.device) -> list[torch.Tensor]:
    """Stack same-shaped MLPs into batched parameters (leading dimension = MLP index).

    Args:
        mlps: each a ``init_mlp`` parameter list.
        device: where the stacked tensors live.

    Returns:
        Leaf tensors ``[w0 (M, in, out), b0 (M, 1, out), ...]`` that require grad.
    """
    return [torch.stack(layer).to(device).requires_grad_() for layer in zip(*mlps, strict=True)]


def mlp_forward(params: Sequence[torch.Tensor], x: torch.Tensor) -> torch.Tensor:
    """Evaluate M stacked MLPs: ReLU hidden layers, linear output.

    Args:
        params: ``[w0, b0, w1, b1, ...]`` as from ``stack_mlps``.
        x: (M, B, in) inputs, row m for MLP m.

    Returns:
        (M, B, out) outputs.
    """
    *hidden, last = zip(params[::2], params[1::2], strict=True)
    for weight, bias in hidden:
        x = torch.baddbmm(bias, x, weight).relu_()
    return torch.baddbmm(last[1], x, last[0])


def critic_values(
    params: Sequence[torch.Tensor], observations: torch.Tensor, actions: torch.Tensor
) -> torch.Tensor:
    """Q-values of n critics per skill, stacked critic-major (critic j of skill k at j*K + k).

    Args:
        params: stacked parameters of n*K critics.
        observations: (K, B, obs_dim) normalised.
        actions: (K, B, action_dim) normalised.

    Returns:
        (n, K, B) Q-values.
    """
    x = torch.cat([observations, actions], dim=-1)
    copies = params[0].shape[0] // x.shape[0]
    return mlp_forward(params, x.repeat(copies, 1, 1)).view(copies, *x.shape[:2])


# ----------------------------------------------------------------------------- trainer


class TD3BC:
    """K TD3+BC learners updated together; ``train_step`` is one update of all of them."""

    def __init__(
        self,
        config: TD3BCConfig,
        seeds: Sequence[int],
        obs_dim: int = OBS_DIM,
        action_dim: int = ACTION_DIM,
        device: str | torch.device = "cpu",
    ) -> None:
        """Initialise each skill's actor and twin critics from its own seed.

        Args:
            config: hyper-parameters.
            seeds: one seed per skill (K = ``len(seeds)``).
            obs_dim: observation size.
            action_dim: action size.
            device: "cpu" or "cuda"; weights are drawn on the CPU, so the device does not
                change the initial weights.
        """
        self.config = config
        self.device = torch.device(device)
        self.num_skills = len(seeds)
        self.steps = 0
        actors, critics = [], []
        for seed in seeds:
            generator = torch.Generator().manual_seed(seed)
            actors.append(init_mlp((obs_dim, *config.hidden_sizes, action_dim), generator))
            critic_sizes = (obs_dim + action_dim, *config.hidden_sizes, 1)
            critics.append([init_mlp(critic_sizes, generator) for _ in range(2)])
        twins = [critic[j] for j in range(2) for critic in critics]
        self.actor = stack_mlps(actors, self.device)
        self.critic = stack_mlps(twins, self.device)
        self.actor_target = [p.detach().clone() for p in self.actor]
        self.critic_target = [p.detach().clone() for p in self.critic]
        fused = self.device.type in ("cpu", "cuda")
        self.actor_optimizer = torch.optim.Adam(self.actor, lr=config.actor_lr, fused=fused)
        self.critic_optimizer = torch.optim.Adam(self.critic, lr=config.critic_lr, fused=fused)

    def actions(self, observations: torch.Tensor) -> torch.Tensor:
        """The actors' normalised actions.

        Args:
            observations: (K, B, obs_dim) normalised observations, row k for skill k.

        Returns:
            (K, B, action_dim) actions in [-1, 1].
        """
        with torch.no_grad():
            return torch.tanh(mlp_forward(self.actor, observations.to(self.device)))

    def train_step(self, batch: Batch) -> dict[str, torch.Tensor]:
        """One TD3+BC update of every skill: critics always, actors every ``policy_freq``.

        Args:
            batch: from ``BatchedReplay.sample``.

        Returns:
            Per-skill (K,) detached tensors: ``critic_loss`` and ``q_mean`` (Q1 on the data)
            every step; ``actor_loss``, ``bc_loss`` and ``lam`` (lambda) on actor steps.
        """
        cfg = self.config
        self.steps += 1
        with torch.no_grad():
            noise = (batch.noise * cfg.policy_noise).clamp(-cfg.noise_clip, cfg.noise_clip)
            next_actions = torch.tanh(mlp_forward(self.actor_target, batch.next_observations))
            next_actions = (next_actions + noise).clamp(-1.0, 1.0)
            target_q = critic_values(self.critic_target, batch.next_observations, next_actions)
            target_q = batch.rewards + cfg.gamma * (1.0 - batch.dones) * target_q.amin(0)
            if cfg.target_q_range is not None:
                target_q = target_q.clamp(*cfg.target_q_range)

        q = critic_values(self.critic, batch.observations, batch.actions)
        critic_loss = (q - target_q).square().mean(-1).sum(0)
        self.critic_optimizer.zero_grad(set_to_none=True)
        critic_loss.sum().backward()
        self.critic_optimizer.step()
        logs = {"critic_loss": critic_loss.detach(), "q_mean": q[0].detach().mean(-1)}

        if self.steps % cfg.policy_freq == 0:
            pi = torch.tanh(mlp_forward(self.actor, batch.observations))
            q1_params = [p[: self.num_skills].detach() for p in self.critic]
            q1 = critic_values(q1_params, batch.observations, pi)[0]
            lam = cfg.alpha / q1.abs().mean(-1).detach()
            weights = bc_weights(batch.actions, cfg.gripper_switch_weight)
            bc_loss = (weights * (pi - batch.actions).square()).mean((1, 2))
            actor_loss = -lam * q1.mean(-1) + bc_loss
            self.actor_optimizer.zero_grad(set_to_none=True)
            actor_loss.sum().backward()
            self.actor_optimizer.step()
            with torch.no_grad():
                for target, source in zip(
                    self.actor_target + self.critic_target, self.actor + self.critic, strict=True
                ):
                    target.lerp_(source, cfg.tau)
            logs.update(actor_loss=actor_loss.detach(), bc_loss=bc_loss.detach(), lam=lam)
        return logs

    def keep(self, skills: Sequence[int]) -> None:
        """Go on training the skills at positions ``skills`` only (in that order): their
        actors, critics, targets and Adam states are kept, the others dropped, so each kept
        skill's update continues as before (but for the last bits of batched kernels)."""
        positions = list(skills)
        twins = positions + [self.num_skills + k for k in positions]  # critic-major
        self.actor_target = [p[positions].clone() for p in self.actor_target]
        self.critic_target = [p[twins].clone() for p in self.critic_target]
        self.actor, self.actor_optimizer = _kept_optimised(
            self.actor, self.actor_optimizer, positions
        )
        self.critic, self.critic_optimizer = _kept_optimised(
            self.critic, self.critic_optimizer, twins
        )
        self.num_skills = len(positions)

    def actor_layers(self, skill: int) -> list[tuple[np.ndarray, np.ndarray]]:
        """One skill's actor as numpy arrays (for checkpoints).

        Args:
            skill: index k of the skill in this trainer.

        Returns:
            ``[(weight (in, out), bias (out,)), ...]`` float32; ReLU between layers, tanh
            after the last.
        """
        arrays = [p[skill].detach().cpu().numpy().copy() for p in self.actor]
        return [(w, b.reshape(-1)) for w, b in zip(arrays[::2], arrays[1::2], strict=True)]


def _kept_optimised(
    params: list[torch.Tensor], optimizer: torch.optim.Adam, rows: list[int]
) -> tuple[list[torch.Tensor], torch.optim.Adam]:
    """The stacked parameters' ``rows`` as new leaves, with an Adam optimiser holding the
    same settings and those rows of its moment estimates (and its step counts)."""
    kept = [p.detach()[rows].clone().requires_grad_() for p in params]
    group = {k: v for k, v in optimizer.param_groups[0].items() if k != "params"}
    kept_optimizer = torch.optim.Adam(kept, **group)
    for old, new in zip(params, kept, strict=True):
        state = optimizer.state.get(old)
        if state:
            kept_optimizer.state[new] = {
                key: value if value.ndim == 0 else value[rows].clone()
                for key, value in state.items()
            }
    return kept, kept_optimizer
