"""A fenced region's parts and the ground under it (``controllers.evidence``), on hand-made
masks: a road user counted in two fences is one region, and the ground depth under a
region counts only where the fence judges the ground."""

import numpy as np

from controllers.evidence import contact_depth, fenced_blobs

H, W = 40, 60
THR = np.array([1.0, 2.0])  # [s]
DEPTH = np.linspace(100.0, 2.0, H)  # [m] a stand-in ground depth per row, nearer lower down


def _blobs(inside, lowest_rows, join_rows, maps=None):
    touch = np.zeros_like(inside)
    touch[max(lowest_rows) - 1 : max(lowest_rows) + 1] = True
    maps = np.stack([inside.astype(np.float32)] * len(THR)) if maps is None else maps
    return fenced_blobs(inside, touch, maps, THR, 0.5, 4, DEPTH, lowest_rows, join_rows)


def test_a_road_user_counted_in_two_fences_with_rows_between_is_one_region():
    inside = np.zeros((H, W), dtype=bool)
    inside[10:18, 20:24] = True  # the upper body, counted in the larger fence
    inside[20:30, 21:25] = True  # the legs, counted in the smaller one, two rows lower
    joined = _blobs(inside, [29, 17], join_rows=3)
    assert len(joined) == 1 and (joined[0].u_left, joined[0].u_right) == (20.0, 24.0)
    assert joined[0].mask.sum() == inside.sum()
    # without joining, only the legs stand on the road's lowest rows: the upper body is lost
    apart = _blobs(inside, [29, 17], join_rows=0)
    assert len(apart) == 1 and apart[0].mask.sum() == 40
    # side by side parts stay apart
    inside[:] = False
    inside[20:30, 10:14] = True
    inside[20:30, 16:20] = True
    assert len(_blobs(inside, [29, 17], join_rows=3)) == 2


def test_the_ground_under_a_region_counts_only_on_the_fence_s_counted_rows():
    fenced = np.zeros((H, W), dtype=bool)
    region = np.zeros_like(fenced)
    region[10:20, 20:25] = True
    fenced |= region
    # it ends inside the counted rows (down to row 30): it stands on the ground below it
    assert contact_depth(fenced, region, 20, 24, DEPTH, lowest_row=30) == DEPTH[20]
    # it ends on the lowest counted row: the free row below lies where the fence is not judged
    assert contact_depth(fenced, region, 20, 24, DEPTH, lowest_row=19) is None
    # the fenced road runs on below it to the image's bottom
    fenced[20:, 18:27] = True
    assert contact_depth(fenced, region, 20, 24, DEPTH, lowest_row=30) is None
