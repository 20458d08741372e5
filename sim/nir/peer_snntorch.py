"""The independent NIR consumer and the training framework: snnTorch, run in its own environment
(``scripts/crosscheck_env.sh``; this file imports nothing of cuneate and is run by path).

``python peer_snntorch.py run GRAPH.nir INPUT.npy OUT.npy``
    ``snntorch.import_nir.import_from_nir`` on the graph, the input (steps, n_in) fed one step at
    a time (float32), the output layer's spikes saved as (steps, n_out).
``python peer_snntorch.py train DATA.npz OUT_DIR BITS QAT SEED HIDDEN EPOCHS``
    Train ``Linear -> Leaky -> Linear -> Leaky`` (no biases) with snnTorch's surrogate gradient
    on the training trials of DATA.npz (``x_train`` (trials, steps, n_in) spikes, ``y_train``),
    the loss the cross-entropy of the output spike counts. ``BITS`` 0 trains in float; with
    ``QAT`` 1 the forward pass uses weights fake-quantized to ``BITS`` (symmetric, per-tensor
    scale = max |w| / (2**(BITS-1) - 1), straight-through gradient). Writes ``OUT_DIR/model.nir``
    (``snntorch.export_nir.export_to_nir`` of the float weights, or of the quantized ones when
    ``BITS`` > 0) and prints one JSON line: snnTorch's own test accuracy (float32, the weights
    it exports), training time.
"""

import json
import sys
import time


def _load_graph(path):
    import nir
    return nir.read(path)


def run(graph_path, input_path, out_path):
    import numpy as np
    import torch
    from snntorch import utils
    from snntorch.import_nir import import_from_nir
    net = import_from_nir(_load_graph(graph_path))
    x = torch.from_numpy(np.load(input_path).astype(np.float32))
    utils.reset(net)
    outs = []
    with torch.no_grad():
        for k in range(x.shape[0]):
            o = net(x[k:k + 1])
            o = o[0] if isinstance(o, tuple) else o
            outs.append(o.reshape(-1).numpy().copy())
    np.save(out_path, np.array(outs) > 0.5)


def _quant(w, bits):
    import torch
    if not bits:
        return w
    q = 2 ** (bits - 1) - 1
    scale = w.detach().abs().max().clamp(min=1e-12) / q
    wq = torch.round(w / scale).clamp(-q, q) * scale
    return w + (wq - w).detach()          # straight-through


def train(data_path, out_dir, bits, qat, seed, hidden, epochs):
    import os

    import numpy as np
    import snntorch as snn
    import torch
    from snntorch import surrogate
    from snntorch.export_nir import export_to_nir
    torch.manual_seed(seed)
    torch.set_num_threads(1)   # tiny tensors: extra threads only spin
    d = np.load(data_path)
    xtr = torch.from_numpy(d["x_train"].astype(np.float32))
    ytr = torch.from_numpy(d["y_train"].astype(np.int64))
    xte = torch.from_numpy(d["x_test"].astype(np.float32))
    yte = torch.from_numpy(d["y_test"].astype(np.int64))
    n_in, n_cls = xtr.shape[2], int(ytr.max()) + 1
    beta, thr = float(d["beta"]), float(d["threshold"])
    fc1 = torch.nn.Linear(n_in, hidden, bias=False)
    fc2 = torch.nn.Linear(hidden, n_cls, bias=False)
    sg = surrogate.fast_sigmoid(slope=10)
    lif1 = snn.Leaky(beta=beta, threshold=thr, spike_grad=sg, reset_mechanism="zero",
                     reset_delay=False)
    lif2 = snn.Leaky(beta=beta, threshold=thr, spike_grad=sg, reset_mechanism="zero",
                     reset_delay=False)
    use_q = bits if qat else 0

    def forward(x, qbits):
        m1, m2 = lif1.init_leaky(), lif2.init_leaky()
        w1, w2 = _quant(fc1.weight, qbits), _quant(fc2.weight, qbits)
        count = 0
        for k in range(x.shape[1]):
            s1, m1 = lif1(x[:, k] @ w1.T, m1)
            s2, m2 = lif2(s1 @ w2.T, m2)
            count = count + s2
        return count

    opt = torch.optim.Adam(list(fc1.parameters()) + list(fc2.parameters()), lr=2e-3)
    t0 = time.perf_counter()
    for _ in range(epochs):
        perm = torch.randperm(xtr.shape[0])
        for i in range(0, xtr.shape[0], 32):
            idx = perm[i:i + 32]
            c = forward(xtr[idx], use_q)
            loss = torch.nn.functional.cross_entropy(c * 0.5, ytr[idx])
            opt.zero_grad()
            loss.backward()
            opt.step()
    train_s = time.perf_counter() - t0
    with torch.no_grad():
        c = forward(xte, bits)
        acc = float((c.argmax(1) == yte).float().mean())
        if bits:
            fc1.weight.copy_(_quant(fc1.weight, bits))
            fc2.weight.copy_(_quant(fc2.weight, bits))
    os.makedirs(out_dir, exist_ok=True)
    # the exported copy: neurons that keep their state inside (a Sequential passes spikes on)
    # with per-neuron parameters (NIR's shape inference needs them)
    def exported(n):
        return snn.Leaky(beta=torch.full((n,), beta), threshold=torch.full((n,), thr),
                         spike_grad=sg, reset_mechanism="zero", reset_delay=False,
                         init_hidden=True)
    net = torch.nn.Sequential(fc1, exported(hidden), fc2, exported(n_cls))
    graph = export_to_nir(net, xte[0, 0])
    import nir
    nir.write(os.path.join(out_dir, "model.nir"), graph)
    print(json.dumps({"accuracy": acc, "train_s": train_s, "bits": bits, "qat": bool(qat)}))


if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "run":
        run(*sys.argv[2:5])
    elif cmd == "train":
        a = sys.argv[2:]
        train(a[0], a[1], int(a[2]), int(a[3]), int(a[4]), int(a[5]), int(a[6]))
    else:
        raise SystemExit(f"unknown command {cmd!r}")
