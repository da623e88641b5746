"""Seed 001's image networks in plain torch (no torchvision build on CPU machines): AlexNet,
VGG-16, VGG-19 and ResNet-50 at full depth, as regressors of one value (the remaining discharge
time) from a grey frame; and the CNN-LSTM of its process prediction (NRRP over time).

The four backbones follow the torchvision definitions layer for layer (the same convolutions,
pools, adaptive average pool to 6x6 / 7x7 / 1x1, and classifier widths): built with
`in_channels=3, outputs=1000` each has exactly torchvision's ImageNet parameter count
(tests/py/test_cnn.py), so "AlexNet" here is the AlexNet of the seed's comparison. For seed 001
they take one grey channel and give one output. The adaptive pool lets them take frames smaller
than 224 x 224 (the 2-core comparison uses reduced frames; docs/seed001.md says which), down to
the smallest size each downsampling chain accepts (`min_input`).

AlexNet-FC (seed 001, Fig. 5) is the AlexNet feature extractor followed by a fully connected
regression head: `alexnet_fc`. The CNN-LSTM (Fig. 7): four convolutions of 32, 64, 128 and 25
kernels, flattened to 1024 features, four stacked LSTM layers of 4, 8, 16 and 32 units, and a
linear read-out of the NRRP; it reads a sequence of frames and gives the NRRP at every one."""
from __future__ import annotations

import torch
from torch import nn


def _alexnet_features(in_channels: int) -> nn.Sequential:
    return nn.Sequential(
        nn.Conv2d(in_channels, 64, 11, stride=4, padding=2), nn.ReLU(inplace=True), nn.MaxPool2d(3, 2),
        nn.Conv2d(64, 192, 5, padding=2), nn.ReLU(inplace=True), nn.MaxPool2d(3, 2),
        nn.Conv2d(192, 384, 3, padding=1), nn.ReLU(inplace=True),
        nn.Conv2d(384, 256, 3, padding=1), nn.ReLU(inplace=True),
        nn.Conv2d(256, 256, 3, padding=1), nn.ReLU(inplace=True), nn.MaxPool2d(3, 2))


class AlexNet(nn.Module):
    min_input = 63  # conv 11/4 and three 3/2 max pools

    def __init__(self, in_channels: int = 1, outputs: int = 1, dropout: float = 0.5):
        super().__init__()
        self.features = _alexnet_features(in_channels)
        self.pool = nn.AdaptiveAvgPool2d((6, 6))
        self.head = nn.Sequential(
            nn.Dropout(dropout), nn.Linear(256 * 6 * 6, 4096), nn.ReLU(inplace=True),
            nn.Dropout(dropout), nn.Linear(4096, 4096), nn.ReLU(inplace=True), nn.Linear(4096, outputs))

    def forward(self, x):
        return self.head(torch.flatten(self.pool(self.features(x)), 1))


class AlexNetFC(nn.Module):
    """AlexNet's convolutional features, then a fully connected regression head (seed 001's
    point-to-point model): 9216 -> 1024 -> 256 -> 1 with ReLU, dropout before the first."""
    min_input = 63

    def __init__(self, in_channels: int = 1, dropout: float = 0.5):
        super().__init__()
        self.features = _alexnet_features(in_channels)
        self.pool = nn.AdaptiveAvgPool2d((6, 6))
        self.head = nn.Sequential(nn.Dropout(dropout), nn.Linear(256 * 6 * 6, 1024), nn.ReLU(inplace=True),
                                  nn.Linear(1024, 256), nn.ReLU(inplace=True), nn.Linear(256, 1))

    def forward(self, x):
        return self.head(torch.flatten(self.pool(self.features(x)), 1))


VGG_LAYERS = {16: (64, 64, "M", 128, 128, "M", 256, 256, 256, "M", 512, 512, 512, "M", 512, 512, 512, "M"),
              19: (64, 64, "M", 128, 128, "M", 256, 256, 256, 256, "M", 512, 512, 512, 512, "M", 512, 512, 512, 512, "M")}


class VGG(nn.Module):
    min_input = 32  # five 2/2 max pools

    def __init__(self, depth: int = 16, in_channels: int = 1, outputs: int = 1, dropout: float = 0.5):
        super().__init__()
        layers, c = [], in_channels
        for v in VGG_LAYERS[depth]:
            if v == "M":
                layers.append(nn.MaxPool2d(2, 2))
            else:
                layers += [nn.Conv2d(c, v, 3, padding=1), nn.ReLU(inplace=True)]
                c = v
        self.features = nn.Sequential(*layers)
        self.pool = nn.AdaptiveAvgPool2d((7, 7))
        self.head = nn.Sequential(
            nn.Linear(512 * 7 * 7, 4096), nn.ReLU(inplace=True), nn.Dropout(dropout),
            nn.Linear(4096, 4096), nn.ReLU(inplace=True), nn.Dropout(dropout), nn.Linear(4096, outputs))
        # torchvision's initialisation: with torch's default (Kaiming-uniform, a = sqrt 5) the
        # signal fades through 16-19 ReLU layers and training stalls at the mean
        for m in self.modules():
            if isinstance(m, nn.Conv2d):
                nn.init.kaiming_normal_(m.weight, mode="fan_out", nonlinearity="relu")
                nn.init.zeros_(m.bias)
            elif isinstance(m, nn.Linear):
                nn.init.normal_(m.weight, 0.0, 0.01)
                nn.init.zeros_(m.bias)

    def forward(self, x):
        return self.head(torch.flatten(self.pool(self.features(x)), 1))


class Bottleneck(nn.Module):
    """ResNet v1.5 bottleneck (the stride on the 3x3 convolution, as torchvision)."""
    expansion = 4

    def __init__(self, c_in: int, width: int, stride: int = 1):
        super().__init__()
        c_out = width * self.expansion
        self.body = nn.Sequential(
            nn.Conv2d(c_in, width, 1, bias=False), nn.BatchNorm2d(width), nn.ReLU(inplace=True),
            nn.Conv2d(width, width, 3, stride=stride, padding=1, bias=False), nn.BatchNorm2d(width), nn.ReLU(inplace=True),
            nn.Conv2d(width, c_out, 1, bias=False), nn.BatchNorm2d(c_out))
        self.shortcut = (nn.Sequential(nn.Conv2d(c_in, c_out, 1, stride=stride, bias=False), nn.BatchNorm2d(c_out))
                         if stride != 1 or c_in != c_out else nn.Identity())
        self.relu = nn.ReLU(inplace=True)

    def forward(self, x):
        return self.relu(self.body(x) + self.shortcut(x))


class ResNet50(nn.Module):
    min_input = 32  # stride-2 stem, a 3/2 max pool and three stride-2 stages

    def __init__(self, in_channels: int = 1, outputs: int = 1):
        super().__init__()
        self.stem = nn.Sequential(nn.Conv2d(in_channels, 64, 7, stride=2, padding=3, bias=False), nn.BatchNorm2d(64),
                                  nn.ReLU(inplace=True), nn.MaxPool2d(3, 2, padding=1))
        stages, c = [], 64
        for width, blocks, stride in ((64, 3, 1), (128, 4, 2), (256, 6, 2), (512, 3, 2)):
            for b in range(blocks):
                stages.append(Bottleneck(c, width, stride if b == 0 else 1))
                c = width * Bottleneck.expansion
        self.stages = nn.Sequential(*stages)
        self.pool = nn.AdaptiveAvgPool2d((1, 1))
        self.head = nn.Linear(c, outputs)
        for m in self.modules():  # torchvision's initialisation
            if isinstance(m, nn.Conv2d):
                nn.init.kaiming_normal_(m.weight, mode="fan_out", nonlinearity="relu")
            elif isinstance(m, nn.BatchNorm2d):
                nn.init.ones_(m.weight)
                nn.init.zeros_(m.bias)

    def forward(self, x):
        return self.head(torch.flatten(self.pool(self.stages(self.stem(x))), 1))


class CNNLSTM(nn.Module):
    """Frames (batch, time, 1, H, W) -> NRRP (batch, time). Each frame through four 3x3
    convolutions (32, 64, 128, 25 kernels, each followed by ReLU and a 2x2 max pool) and an
    adaptive pool to 25 x 6 x 7 = 1050 -> a linear map to 1024 features ("flatten to 1024");
    then LSTM layers of 4, 8, 16, 32 units over time and a linear read-out."""

    def __init__(self, in_channels: int = 1, lstm_units=(4, 8, 16, 32)):
        super().__init__()
        layers, c = [], in_channels
        for k in (32, 64, 128, 25):
            layers += [nn.Conv2d(c, k, 3, padding=1), nn.ReLU(inplace=True), nn.MaxPool2d(2, 2)]
            c = k
        self.cnn = nn.Sequential(*layers, nn.AdaptiveAvgPool2d((6, 7)), nn.Flatten(), nn.Linear(25 * 6 * 7, 1024),
                                 nn.ReLU(inplace=True))
        self.lstms = nn.ModuleList()
        width = 1024
        for u in lstm_units:
            self.lstms.append(nn.LSTM(width, u, batch_first=True))
            width = u
        self.out = nn.Linear(width, 1)
        # He initialisation of the convolutions and the 1024 map (torch's default shrinks the
        # signal ~2x per layer; behind four small LSTMs the output then hardly depends on the
        # frames, and training stalled at the targets' mean), and each LSTM's forget gate
        # biased open (+1), the usual remedy for a stack of them
        for m in self.modules():
            if isinstance(m, (nn.Conv2d, nn.Linear)) and m is not self.out:
                nn.init.kaiming_normal_(m.weight, mode="fan_in", nonlinearity="relu")
                nn.init.zeros_(m.bias)
        for lstm in self.lstms:
            h = lstm.hidden_size
            nn.init.xavier_uniform_(lstm.weight_ih_l0)  # gates not saturated by the 1024 inputs
            nn.init.orthogonal_(lstm.weight_hh_l0)
            with torch.no_grad():
                lstm.bias_ih_l0[h:2 * h].fill_(1.0)
                lstm.bias_hh_l0[h:2 * h].zero_()

    min_input = 16  # four 2/2 max pools

    def forward(self, frames):
        b, t = frames.shape[:2]
        # particles bright on a dark background: the frames are dark spheres on white
        z = self.cnn(1.0 - frames.reshape(b * t, *frames.shape[2:])).reshape(b, t, -1)
        for lstm in self.lstms:
            z, _ = lstm(z)
        return self.out(z).squeeze(-1)


BACKBONES = {"alexnet": lambda **k: AlexNet(**k), "resnet50": lambda **k: ResNet50(**k),
             "vgg16": lambda **k: VGG(16, **k), "vgg19": lambda **k: VGG(19, **k)}


def parameter_count(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
