"""PVT³ (the icub20 and biotac20 presets of DESIGN.md) in PyTorch, for the training-speed comparison with candle.

Before timing, the model loads the golden weights and must reproduce the golden logits, which
proves it is the same function as the candle model. It then times optimiser steps exactly as
`pvt3 bench train` does (AdamW, label smoothing 0.1, dropout 0.1, gradient clipping 1.0, random
inputs) and prints one JSON line.
"""

import argparse
import json
import pathlib
import time

import numpy as np
import torch
import torch.nn.functional as F
from safetensors.numpy import load_file
from torch import nn

GOLDEN = pathlib.Path(__file__).resolve().parent.parent / "tests" / "golden" / "icub20"


class Attention(nn.Module):
    def __init__(self, dim, heads, dim_head, dropout):
        super().__init__()
        self.heads, self.dim_head, self.inner = heads, dim_head, heads * dim_head
        self.qkv = nn.Linear(dim, 3 * self.inner, bias=False)
        self.out = nn.Linear(self.inner, dim)
        self.channel_mask = nn.Parameter(torch.ones(self.inner))
        self.drop = nn.Dropout(dropout)

    def forward(self, x):
        b, n, _ = x.shape
        q, k, v = (t * self.channel_mask for t in self.qkv(x).chunk(3, dim=-1))
        q, k, v = (t.reshape(b, n, self.heads, self.dim_head).transpose(1, 2) for t in (q, k, v))
        attn = (q @ k.transpose(-1, -2) * self.dim_head**-0.5).softmax(dim=-1)
        out = (attn @ v).transpose(1, 2).reshape(b, n, self.inner)
        return self.drop(self.out(out))


class FeedForward(nn.Module):
    def __init__(self, dim, mlp, dropout):
        super().__init__()
        self.fc1, self.fc2 = nn.Linear(dim, mlp), nn.Linear(mlp, dim)
        self.channel_mask = nn.Parameter(torch.ones(mlp))
        self.drop = nn.Dropout(dropout)

    def forward(self, x):
        h = self.drop(F.gelu(self.fc1(x)) * self.channel_mask)
        return self.drop(self.fc2(h))


class Block(nn.Module):
    def __init__(self, cfg):
        super().__init__()
        d = cfg["dim"]
        self.attn_norm, self.ffn_norm = nn.LayerNorm(d), nn.LayerNorm(d)
        self.attn = Attention(d, cfg["heads"], cfg["dim_head"], cfg["dropout"])
        self.ffn = FeedForward(d, cfg["mlp_dim"], cfg["dropout"])

    def forward(self, x):
        x = x + self.attn(self.attn_norm(x))
        return x + self.ffn(self.ffn_norm(x))


class Transformer(nn.Module):
    def __init__(self, cfg, depth):
        super().__init__()
        self.layers = nn.ModuleList(Block(cfg) for _ in range(depth))
        self.norm = nn.LayerNorm(cfg["dim"])

    def forward(self, x):
        for layer in self.layers:
            x = layer(x)
        return self.norm(x[:, 0])


class Pvt3(nn.Module):
    def __init__(self, cfg):
        super().__init__()
        self.cfg = cfg
        d, t = cfg["dim"], cfg["frames"] // cfg["tubelet"]
        self.n = (cfg["height"] // cfg["patch_height"]) * (cfg["width"] // cfg["patch_width"])
        self.patch_embed = nn.Linear(cfg["tubelet"] * cfg["patch_height"] * cfg["patch_width"], d)
        self.frame_mask = nn.Parameter(torch.ones(t))
        self.pos_embed = nn.Parameter(0.02 * torch.randn(1, t, self.n + 1, d))
        self.space_cls = nn.Parameter(0.02 * torch.randn(1, 1, d))
        self.temporal_cls = nn.Parameter(0.02 * torch.randn(1, 1, d))
        self.space = Transformer(cfg, cfg["space_depth"])
        self.temporal = Transformer(cfg, cfg["time_depth"])
        self.head_norm = nn.LayerNorm(d)
        self.head = nn.Linear(d, cfg["classes"])
        self.drop = nn.Dropout(cfg["dropout"])

    def forward(self, x):  # [b, h, w, t]
        c = self.cfg
        ph, pw, tub = c["patch_height"], c["patch_width"], c["tubelet"]
        b, t = x.shape[0], x.shape[-1] // tub
        gh, gw = c["height"] // ph, c["width"] // pw
        # [b, gh, ph, gw, pw, t, tubelet] -> [b, t, gh, gw, tubelet, ph, pw], as pvt3's patchify.
        x = x.reshape(b, gh, ph, gw, pw, t, tub).permute(0, 5, 1, 3, 6, 2, 4).reshape(b, t, gh * gw, tub * ph * pw)
        e = self.patch_embed(x) * self.frame_mask[None, :, None, None]
        e = torch.cat([self.space_cls[:, None].expand(b, t, 1, -1), e], dim=2) + self.pos_embed
        e = self.drop(e)
        s = self.space(e.reshape(b * t, self.n + 1, -1)).reshape(b, t, -1)
        z = self.temporal(torch.cat([self.temporal_cls.expand(b, 1, -1), s], dim=1))
        return self.head(self.head_norm(z))


def icub20(dropout):
    return dict(height=6, width=10, frames=75, patch_height=3, patch_width=5, tubelet=1, dim=20, space_depth=4,
                time_depth=4, heads=1, dim_head=64, mlp_dim=40, classes=20, dropout=dropout)


def biotac20(dropout):
    return dict(icub20(dropout), height=19, width=1, frames=400, patch_height=19, patch_width=1, tubelet=10)


PRESETS = dict(icub20=(icub20, 64272), biotac20=(biotac20, 61872))


def golden_check():
    model = Pvt3(icub20(0.0)).double().eval()
    weights = {k: torch.from_numpy(v.astype(np.float64)) for k, v in load_file(GOLDEN / "weights.safetensors").items()}
    model.load_state_dict(weights, strict=True)
    x = torch.from_numpy(np.load(GOLDEN / "input.npy").astype(np.float64))
    with torch.no_grad():
        err = (model(x) - torch.from_numpy(np.load(GOLDEN / "logits.npy"))).abs().max().item()
    if err > 1e-9:
        raise SystemExit(f"the PyTorch model does not reproduce the golden logits (worst {err:.3e})")
    return err


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--batch-size", type=int, default=32)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--preset", choices=sorted(PRESETS), default="icub20")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    err = golden_check()
    preset, parameters = PRESETS[args.preset]
    cfg = preset(0.1)
    model = Pvt3(cfg).train()
    assert sum(p.numel() for n, p in model.named_parameters() if n != "frame_mask") == parameters
    decay = [p for n, p in model.named_parameters() if n.endswith(".weight") and p.dim() == 2]
    rest = [p for n, p in model.named_parameters() if not (n.endswith(".weight") and p.dim() == 2)]
    opt = torch.optim.AdamW([{"params": decay, "weight_decay": 0.05}, {"params": rest, "weight_decay": 0.0}], lr=2e-3)
    x = torch.randn(args.batch_size, cfg["height"], cfg["width"], cfg["frames"])
    y = torch.arange(args.batch_size) % 20

    def step():
        opt.zero_grad(set_to_none=True)
        loss = F.cross_entropy(model(x), y, label_smoothing=0.1)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        opt.step()

    for _ in range(2):
        step()
    started = time.perf_counter()
    for _ in range(args.steps):
        step()
    per_step = (time.perf_counter() - started) / args.steps
    print(json.dumps(dict(framework=f"pytorch {torch.__version__}", preset=args.preset, batch_size=args.batch_size, steps=args.steps,
                          seconds_per_step=per_step, samples_per_second=args.batch_size / per_step,
                          golden_max_abs_error=err)))


if __name__ == "__main__":
    main()
