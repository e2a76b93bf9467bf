"""The probe's device option: training on a named device and inference that follows the
network's device (a GPU in use; here the CPU and PyTorch's shape-only ``meta`` device)."""

from __future__ import annotations

import numpy as np
import torch

from stereovar.probe.network import MatchingNet, border, dense_features, score_volume
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
