#!/usr/bin/env python3
"""A policy for `fetchscope record --policy "exec:python3 mlp_policy.py"`: a small numpy MLP
served over fetchscope's JSON-lines protocol (docs/guide/your-policy.md).

Protocol: fetchscope writes one JSON object per step on our stdin,
    {"t": 0, "observation": [...], "achieved_goal": [...], "desired_goal": [...]}
and reads one line back on our stdout: the action, 4 numbers (a JSON array here).
stdout carries the actions and nothing else: log to stderr.

The network is 6 -> 8 -> 4: input [achieved_goal, desired_goal], one ReLU layer, tanh out.
Without --weights its weights are set by hand so that it steers the gripper to the goal (each
output is tanh(20 * (goal - grip)), a unit of action being 0.05 m); --weights FILE.npz loads
trained ones (arrays W1 (8, 6), b1 (8,), W2 (4, 8), b2 (4,)).
Runs on Debian's python3 with python3-numpy.
"""
import argparse
import json
import sys

import numpy as np


class MLP:
    def __init__(self, W1, b1, W2, b2):
        self.W1, self.b1, self.W2, self.b2 = W1, b1, W2, b2

    @classmethod
    def hand_set(cls):
        # hidden units: relu(goal - grip) and relu(grip - goal) per axis (6), two unused
        W1 = np.zeros((8, 6))
        for axis in range(3):
            W1[2 * axis, 3 + axis], W1[2 * axis, axis] = 1.0, -1.0
            W1[2 * axis + 1, 3 + axis], W1[2 * axis + 1, axis] = -1.0, 1.0
        W2 = np.zeros((4, 8))
        for axis in range(3):
            W2[axis, 2 * axis], W2[axis, 2 * axis + 1] = 20.0, -20.0  # 1 / 0.05 m
        return cls(W1, np.zeros(8), W2, np.zeros(4))  # output 3, the gripper: 0

    @classmethod
    def load(cls, path):
        w = np.load(path)
        return cls(w["W1"], w["b1"], w["W2"], w["b2"])

    def act(self, obs):
        x = np.concatenate([obs["achieved_goal"], obs["desired_goal"]])
        h = np.maximum(0.0, self.W1 @ x + self.b1)
        return np.tanh(self.W2 @ h + self.b2)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--weights", help="an .npz with W1, b1, W2, b2")
    args = parser.parse_args()
    policy = MLP.load(args.weights) if args.weights else MLP.hand_set()
    # An SB3 model instead (pip install stable-baselines3; trained on the same env id):
    #   from stable_baselines3 import SAC
    #   model = SAC.load("sac_fetch.zip")
    #   act = lambda obs: model.predict({k: np.asarray(v) for k, v in obs.items() if k != "t"},
    #                                   deterministic=True)[0]
    # A PyTorch actor: with torch.no_grad(): actor(torch.as_tensor(x, dtype=torch.float32)).numpy()
    print(f"mlp_policy: serving ({'weights ' + args.weights if args.weights else 'hand-set weights'})",
          file=sys.stderr)
    for line in sys.stdin:
        obs = {k: np.asarray(v, dtype=np.float64) if isinstance(v, list) else v
               for k, v in json.loads(line).items()}
        action = policy.act(obs)
        print(json.dumps([float(a) for a in action]), flush=True)


if __name__ == "__main__":
    main()
