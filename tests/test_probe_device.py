"""The probe's device option: training on a named device and inference that follows the
network's device (the CPU and PyTorch's shape-only ``meta`` device everywhere; a CUDA GPU
where one is present)."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import torch

from stereovar.probe.network import (
    MatchingNet,
    border,
    dense_features,
    score_volume,
    wta_disparity,
)
from stereovar.probe.training import TrainingFrame, TrainSettings, train_matcher

SETTINGS = TrainSettings(steps=3, crops=2, crop_rows=8, crop_cols=16)


def frames(seed: int = 0) -> list[TrainingFrame]:
    """Two random 32x64 pairs with a disparity of 2 px everywhere."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(2):
        right = rng.random((32, 64), dtype=np.float32)
        left = np.roll(right, 2, axis=1)
        out.append(TrainingFrame(left, right, np.full((32, 64), 2.0, np.float32), -1))
    return out


def test_training_on_a_named_device_matches_the_default_and_returns_a_cpu_network():
    data = frames()
    plain, plain_history = train_matcher(data, SETTINGS, seed=3)
    named, named_history = train_matcher(data, SETTINGS, seed=3, device=torch.device("cpu"))
    assert named_history["loss"] == plain_history["loss"]
    for (name, a), (_, b) in zip(
        plain.state_dict().items(), named.state_dict().items(), strict=True
    ):
        assert torch.equal(a, b), name
        assert b.device.type == "cpu", name


def test_inference_follows_the_network_device():
    net = MatchingNet().to("meta")
    image = np.zeros((20, 30), np.float32)
    features = dense_features(net, image)
    b = border()
    assert features.device.type == "meta"
    assert tuple(features.shape) == (net.features, 20 - 2 * b, 30 - 2 * b)
    volume = score_volume(features, features, sign=1, max_disparity=5)
    assert volume.device.type == "meta"
    assert tuple(volume.shape) == (6, 20 - 2 * b, 30 - 2 * b)


@pytest.mark.skipif(
    not torch.cuda.is_available(),
    reason="no CUDA device (a CPU-only PyTorch build, or no GPU on this machine)",
)
def test_training_and_inference_on_cuda_agree_with_the_cpu():
    data = frames()
    cpu, cpu_history = train_matcher(data, SETTINGS, seed=3)
    gpu, gpu_history = train_matcher(data, SETTINGS, seed=3, device="cuda")
    # the same seeded weights and the same crops (drawn on the CPU): the first step's loss
    # agrees up to the GPU's float arithmetic (TF32 convolutions), every step is scored
    assert gpu_history["triplets"] == cpu_history["triplets"]
    assert gpu_history["loss"][0] == pytest.approx(cpu_history["loss"][0], rel=1e-2)
    assert np.isfinite(gpu_history["loss"]).all()
    for name, value in gpu.state_dict().items():  # the network comes back on the CPU
        assert value.device.type == "cpu", name
        assert bool(torch.isfinite(value).all()), name
    # inference on the GPU: features, the score volume and the disparities stay there until
    # the winner is read back, and agree with the CPU's for the same network
    on_gpu = copy.deepcopy(cpu).to("cuda")
    left, right = data[0].left, data[0].right
    features = dense_features(on_gpu, left)
    assert features.device.type == "cuda"
    np.testing.assert_allclose(
        features.cpu().numpy(), dense_features(cpu, left).detach().numpy(), rtol=1e-2, atol=1e-2
    )
    volume = score_volume(features, dense_features(on_gpu, right), sign=-1, max_disparity=5)
    b = border()
    assert volume.device.type == "cuda" and tuple(volume.shape) == (6, 32 - 2 * b, 64 - 2 * b)
    on_cpu = wta_disparity(cpu, left, right, sign=-1, max_disparity=5)
    on_cuda = wta_disparity(on_gpu, left, right, sign=-1, max_disparity=5)
    inside = np.isfinite(on_cpu)
    np.testing.assert_array_equal(np.isfinite(on_cuda), inside)
    assert (on_cuda[inside] == on_cpu[inside]).mean() > 0.99
