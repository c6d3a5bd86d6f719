"""Self-distillation from a frozen teacher's flip-averaged maps, and the flip views."""

import dataclasses

import pytest
import torch

from bittc_core.checkpoint import make_payload, save_checkpoint
from bittc_core.errors import CliError
from bittc_core.model import BinaryTTCNet, get_config
from bittc_core.model.flip import flip_views, merge_flip_views
from bittc_core.train import TrainConfig
from bittc_core.train.distill import flip_averaged_logits
from bittc_core.train.losses import lovasz_two_class, masked_bce
from bittc_core.train.targets import eta_labels, sample_eta, sample_shifts_px, valid_mask
from sim.cli import train_cmd
from sim.cli.train_flags import check_train_flags
from tests import train_helpers
from tests.train_helpers import cli_args, fit_fixed_batch


def tiny_net(seed: int) -> BinaryTTCNet:
    torch.manual_seed(seed)
    return BinaryTTCNet(get_config("tiny"))


def test_flip_views_and_merge():
    x = torch.randn(3, 2, 5, 7)
    views = flip_views(x)
    assert views.shape == (6, 2, 5, 7)
    assert torch.equal(views[3:], x.flip(-1))
    assert torch.equal(merge_flip_views(views), x)  # a mirror-consistent output comes back unchanged
    out = torch.randn(6, 2, 5, 7)
    assert torch.allclose(merge_flip_views(out), 0.5 * (out[:3] + out[3:].flip(-1)))
    with pytest.raises(ValueError, match="even batch"):
        merge_flip_views(torch.zeros(3, 1, 2, 2))


def test_flip_averaged_logits_are_the_mean_of_both_views():
    teacher = tiny_net(0).eval()
    prev, latest = torch.rand(2, 3, 48, 96), torch.rand(2, 3, 48, 96)
    eta = torch.tensor([[0.8, 0.95], [0.9, 1.05]])
    with torch.no_grad():
        plain = teacher(prev, latest, eta)
        mirrored = teacher(prev.flip(-1), latest.flip(-1), eta).flip(-1)
    avg = flip_averaged_logits(teacher, prev, latest, eta)
    assert avg.shape == (2, 2, 48, 96)
    assert torch.allclose(avg, 0.5 * (plain + mirrored), atol=1e-5)
    assert not torch.allclose(avg, plain, atol=1e-3)  # the mirrored view does change the maps
    # the average commutes with mirroring the pair
    assert torch.allclose(flip_averaged_logits(teacher, prev.flip(-1), latest.flip(-1), eta).flip(-1), avg, atol=1e-5)
    with pytest.raises(ValueError, match="eval mode"):
        flip_averaged_logits(teacher.train(), prev, latest, eta)


def make_trainer(tmp_path, teacher, **kw):
    return train_helpers.make_trainer(tmp_path, net_seed=1, teacher=teacher, **kw)


def _same_hypotheses(tr, batch, seed: int):
    """The thresholds that ``tr.losses(batch)`` draws after ``tr.gen.manual_seed(seed)``, the
    student's logits on them and the teacher's flip-averaged probabilities."""
    tr.gen.manual_seed(seed)
    b, c, mc = batch["image_prev"].shape[0], tr.cfg, tr.net.config
    sample_shifts_px(b, c.shifts_per_pair, mc.max_shift_px, tr.gen)
    thr = sample_eta(b, c.thresholds_per_pair, c.train_tau_min_s, c.train_eta_max, mc.frame_dt_s, tr.gen)
    with torch.no_grad():
        logits = tr.net(batch["image_prev"], batch["image_latest"], thr)
    soft = torch.sigmoid(flip_averaged_logits(tr.teacher, batch["image_prev"], batch["image_latest"], thr))
    return thr, logits, soft


@pytest.mark.parametrize("actor_weight", [1.0, 2.0])
def test_distill_term_is_the_bce_towards_the_teachers_averaged_maps(tmp_path, actor_weight):
    tr = make_trainer(tmp_path, tiny_net(0), distill_weight=0.7, actor_weight=actor_weight)
    assert not tr.teacher.training and not any(p.requires_grad for p in tr.teacher.parameters())
    batch = next(iter(tr.loader))
    assert (batch["instance"] > 0).any()  # the actor weight has pixels to act on
    tr.gen.manual_seed(5)
    parts = tr.losses(batch)
    base = make_trainer(tmp_path, None, actor_weight=actor_weight)  # same student and hypotheses, no teacher
    base.net.load_state_dict(tr.net.state_dict())
    base.gen.manual_seed(5)
    plain = base.losses(batch)
    assert "distill" not in plain
    # rebuild the distillation target by hand from the same hypotheses
    thr, logits, soft = _same_hypotheses(tr, batch, 5)
    weight = torch.where(batch["instance"] > 0, actor_weight, 1.0)[:, None]
    expected = masked_bce(logits, soft, valid_mask(batch)[:, None], weight)
    assert parts["distill"].item() == pytest.approx(expected.item(), rel=1e-4)
    assert parts["ttc"].item() == pytest.approx(plain["ttc"].item() + 0.7 * expected.item(), rel=1e-4)
    parts["loss"].backward()
    assert all(p.grad is None for p in tr.teacher.parameters())


@pytest.mark.parametrize(("scope", "distill_weight"), [("scenery", 1.0), ("scenery", 0.3), ("scenery-vehicles", 0.5)])
def test_a_scope_puts_the_teachers_maps_where_it_says_and_keeps_the_ground_truth_elsewhere(
    tmp_path, scope, distill_weight
):
    kw = dict(actor_weight=2.0, lovasz_weight=0.5)
    tr = make_trainer(tmp_path, tiny_net(0), distill_weight=distill_weight, distill_scope=scope, **kw)
    batch = dict(next(iter(tr.loader)))
    inst = batch["instance"]
    # the synthetic pairs have no classes: odd instances vehicles (1), even ones pedestrians (2)
    batch["actor_class"] = torch.where(inst > 0, 2 - inst % 2, 0)
    taught = inst == 0 if scope == "scenery" else batch["actor_class"] < 2
    assert taught.any() and (~taught).any() and ((inst > 0) & taught).any() == (scope == "scenery-vehicles")
    tr.gen.manual_seed(5)
    parts = tr.losses(batch)
    # rebuild the mixed targets by hand from the same hypotheses
    thr, logits, soft = _same_hypotheses(tr, batch, 5)
    mask = valid_mask(batch)[:, None]
    target = torch.where(taught[:, None], soft, eta_labels(batch["eta"], thr))
    weight = torch.where(inst > 0, 2.0, 1.0)[:, None]
    weight = torch.where(taught[:, None], distill_weight * weight, weight)
    expected = masked_bce(logits, target, mask, weight) + 0.5 * lovasz_two_class(logits, target.round(), mask)
    assert parts["ttc"].item() == pytest.approx(expected.item(), rel=1e-4)
    logged = masked_bce(logits, soft, mask & taught[:, None])
    assert parts["distill"].item() == pytest.approx(logged.item(), rel=1e-4)
    # the ground truth where the teacher teaches no longer counts: flip it and the loss stays
    flipped = dict(batch, eta=torch.where(taught, 2.0 - batch["eta"], batch["eta"]))
    tr.gen.manual_seed(5)
    assert tr.losses(flipped)["ttc"].item() == pytest.approx(parts["ttc"].item(), rel=1e-4)
    if scope == "scenery-vehicles":
        del batch["actor_class"]
        with pytest.raises(ValueError, match="'scenery-vehicles' needs the dataset's actor classes"):
            tr.losses(batch)


def _teacher_gap_after_steps(tmp_path, distill_weight: float) -> tuple[float, float]:
    """Mean |p_student - p_teacher| on one fixed batch before and after 15 steps on it."""
    teacher = tiny_net(0)
    tr = make_trainer(tmp_path, teacher, distill_weight=distill_weight)
    batch = next(iter(tr.loader))
    thr = torch.tensor([[0.8, 0.9, 0.95, 1.05]]).expand(batch["image_prev"].shape[0], -1)
    soft = torch.sigmoid(flip_averaged_logits(tr.teacher, batch["image_prev"], batch["image_latest"], thr))

    def gap() -> float:
        tr.net.eval()
        with torch.no_grad():
            student = torch.sigmoid(tr.net(batch["image_prev"], batch["image_latest"], thr))
        tr.net.train()
        return float((student - soft).abs().mean())

    before = gap()
    fit_fixed_batch(tr, batch, 15)
    return before, gap()


def test_distillation_pulls_the_student_towards_the_teacher(tmp_path):
    # the loss's optimum per pixel is (y + w p_teacher) / (1 + w): near the teacher for a large w
    before, distilled = _teacher_gap_after_steps(tmp_path, distill_weight=50.0)
    _, ground_truth_only = _teacher_gap_after_steps(tmp_path, distill_weight=1e-9)
    assert distilled < 0.7 * before, (before, distilled)
    assert distilled < 0.7 * ground_truth_only, (distilled, ground_truth_only)


def test_a_run_leaves_the_teacher_unchanged(tmp_path):
    teacher = tiny_net(0)
    frozen = {k: v.clone() for k, v in teacher.state_dict().items()}
    tr = make_trainer(tmp_path, teacher, distill_weight=1.0)
    tr.cfg = dataclasses.replace(tr.cfg, steps=4, val_every=2)
    tr.run()  # training steps and validations
    assert all(torch.equal(frozen[k], v) for k, v in tr.teacher.state_dict().items())


def test_distillation_settings_are_checked(tmp_path):
    with pytest.raises(ValueError, match="needs a teacher"):
        make_trainer(tmp_path, None, distill_weight=1.0)
    with pytest.raises(ValueError, match="a teacher network needs distill_weight > 0"):
        make_trainer(tmp_path, tiny_net(0))
    with pytest.raises(ValueError, match="distill_weight applies to the binary stage, not 'flow'"):
        TrainConfig(stage="flow", distill_weight=1.0)
    with pytest.raises(ValueError, match="distill_weight=-1"):
        TrainConfig(distill_weight=-1.0)
    with pytest.raises(ValueError, match="distill_scope 'actors'"):
        TrainConfig(distill_scope="actors")
    with pytest.raises(ValueError, match="distill_scope 'scenery' needs a teacher"):
        TrainConfig(distill_scope="scenery")
    with pytest.raises(ValueError, match="another network of the student's model config"):
        make_trainer(tmp_path, BinaryTTCNet(get_config("cpu-small")), distill_weight=1.0)


def save_net(path, net, name):
    save_checkpoint(path, make_payload(net, name, {}))
    return str(path)


def test_train_cli_refuses_a_teacher_of_another_config_or_its_own_output(tmp_path):
    other = save_net(tmp_path / "teacher.pt", BinaryTTCNet(get_config("cpu-small")), "cpu-small")
    with pytest.raises(CliError, match="its model config differs from --config 'tiny'"):
        train_cmd.run(cli_args(tmp_path, "--teacher", other))
    assert not (tmp_path / "m.pt").exists() and not (tmp_path / "m.last.pt").exists()
    own = save_net(tmp_path / "m.pt", tiny_net(0), "tiny")
    with pytest.raises(CliError, match="is this run's own checkpoint"):
        train_cmd.run(cli_args(tmp_path, "--teacher", own))
    with pytest.raises(CliError, match="--distill-weight 0.0: must be > 0"):
        check_train_flags(cli_args(tmp_path, "--teacher", other, "--distill-weight", "0"))
    with pytest.raises(CliError, match="--distill-scope scenery: needs --teacher"):
        check_train_flags(cli_args(tmp_path, "--distill-scope", "scenery"))


def test_resume_keeps_the_teacher(tmp_path):
    teacher = save_net(tmp_path / "teacher.pt", tiny_net(0), "tiny")
    assert train_cmd.run(cli_args(tmp_path, "--teacher", teacher, "--distill-weight", "0.5")) == 0
    for extra, match in (
        (["--resume"], "--teacher None"),
        (["--resume", "--teacher", teacher], r"not --teacher .* \(distill weight 1, scope all\)"),
        (
            ["--resume", "--teacher", teacher, "--distill-weight", "0.5", "--distill-scope", "scenery"],
            r"\(distill weight 0.5, scope all\), not .* scope scenery\)",
        ),
        (
            ["--resume", "--teacher", save_net(tmp_path / "t2.pt", tiny_net(3), "tiny"), "--distill-weight", "0.5"],
            "t2.pt",
        ),
    ):
        with pytest.raises(CliError, match=match):
            train_cmd.run(cli_args(tmp_path, *extra))
    args = cli_args(tmp_path, "--resume", "--teacher", teacher, "--distill-weight", "0.5", "--steps", "3")
    assert train_cmd.run(args) == 0


def test_the_cli_stores_the_scope_and_resume_keeps_it(tmp_path):
    from bittc_core.checkpoint import load_checkpoint

    teacher = save_net(tmp_path / "teacher.pt", tiny_net(0), "tiny")
    assert train_cmd.run(cli_args(tmp_path, "--teacher", teacher, "--distill-scope", "scenery")) == 0
    assert load_checkpoint(tmp_path / "m.pt")["train_meta"]["train_config"]["distill_scope"] == "scenery"
    with pytest.raises(CliError, match=r"scope scenery\), not --teacher .* scope all\)"):
        train_cmd.run(cli_args(tmp_path, "--resume", "--teacher", teacher))
    args = cli_args(tmp_path, "--resume", "--teacher", teacher, "--distill-scope", "scenery", "--steps", "3")
    assert train_cmd.run(args) == 0
    # the synthetic pairs have no classes: nothing to keep the road users' ground truth of
    with pytest.raises(CliError, match="--distill-scope scenery-vehicles: --data 'synthetic' has no actor classes"):
        train_cmd.run(cli_args(tmp_path / "sv", "--teacher", teacher, "--distill-scope", "scenery-vehicles"))
    assert not (tmp_path / "sv").exists() or not any((tmp_path / "sv").iterdir())
