"""The paper's published numbers and poses, read once from the shipped files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ftcomp import paper
from ftcomp.paper import paper_poses


def test_paper_poses_are_the_nine_of_table_1() -> None:
    poses = paper_poses()
    assert poses.ids == tuple(str(i) for i in range(1, 10))
    np.testing.assert_allclose(
        poses.rotations[3].as_euler("ZYX", degrees=True), [114.513, 6.333, 158.351], atol=1e-9
    )


def test_every_named_constant_is_the_shipped_json_value() -> None:
    data = json.loads(Path(paper.data_path("huang2020_published_results.json")).read_text())
    assert (data["base_tilt_deg"]["U"], data["base_tilt_deg"]["V"]) == paper.TILT_DEG
    assert paper.TOOL_WEIGHT_N == data["tool_weight_N"] == 3.153
    assert tuple(data["force_bias_N"]) == paper.FORCE_BIAS_N
    assert tuple(data["table4_load_weight_N"]["true"]) == paper.TABLE4_LOAD_WEIGHTS_N


def test_paper_samples_are_tables_1_and_2() -> None:
    samples = paper.paper_samples()
    assert len(samples) == 9 and samples.encoding == "paper_euler"
