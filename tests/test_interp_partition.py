"""Fence paths, partition into patches and pairing of source and target patches."""

from __future__ import annotations

import numpy as np
import pytest

from tests.interp_meshes import annulus, grid, shuffled, signed_area, vid
from tgsis.interpolation import (
    InterpolationSetupError,
    MeshTopology,
    Partition,
    check_disk,
    pair_patches,
    partition_pair,
    partition_surface,
    shortest_edge_path,
    validate_control_vertices,
    validate_fence_paths,
)
from tgsis.mesh import Surface

NX, NY = 9, 7


def v(c: int, r: int, nx: int = NX) -> int:
    return vid(nx, c, r)


def line(a: tuple[int, int], b: tuple[int, int], nx: int = NX) -> list[int]:
    """Grid vertices on a horizontal or vertical segment from a to b."""
    (c0, r0), (c1, r1) = a, b
    n = max(abs(c1 - c0), abs(r1 - r0))
    return [v(c0 + (c1 - c0) * i // n, r0 + (r1 - r0) * i // n, nx) for i in range(n + 1)]


# control vertex sequence of the source (9 x 7 grid) and of a coarser target (5 x 5 grid), pair by pair
SOURCE_CONTROLS = [v(0, 0), v(4, 0), v(8, 0), v(8, 3), v(8, 6), v(4, 6), v(0, 6), v(0, 3), v(4, 3)]
SOURCE_FENCES = [line((0, 3), (4, 3)), line((4, 3), (8, 3)), line((4, 0), (4, 3))]
TARGET_CONTROLS = [
    v(0, 0, 5),
    v(2, 0, 5),
    v(4, 0, 5),
    v(4, 2, 5),
    v(4, 4, 5),
    v(2, 4, 5),
    v(0, 4, 5),
    v(0, 2, 5),
    v(2, 2, 5),
]
TARGET_FENCES = [line((0, 2), (2, 2), 5), line((2, 2), (4, 2), 5), line((2, 0), (2, 2), 5)]


def source() -> Surface:
    return grid(NX, NY, wavy=True)


def target() -> Surface:
    t = grid(5, 5)
    return Surface(t.vertices * [2.0, 1.5, 1.0] + [0.0, 0.0, 5.0], t.triangles)


def check_partition(surface: Surface, part: Partition, controls: list[int]) -> None:
    firsts = [int(p.triangles[0]) for p in part.patches]
    assert firsts[0] == 0 and firsts == sorted(firsts)  # numbered in the order of their lowest triangle
    assert [p.index for p in part.patches] == list(range(len(part.patches)))
    all_tris = np.concatenate([p.triangles for p in part.patches])
    assert np.array_equal(np.sort(all_tris), np.arange(surface.n_cells))  # every triangle in one patch
    topo = MeshTopology.of(surface)
    for p in part.patches:
        assert np.array_equal(part.triangle_patch[p.triangles], np.full(len(p.triangles), p.index))
        assert np.array_equal(p.vertices, np.unique(surface.triangles[p.triangles]))
        sub = Surface(surface.vertices, surface.triangles[p.triangles])
        loop = p.border
        # the border is a border loop of the patch, oriented like its triangles
        steps = set(zip(loop.tolist(), np.roll(loop, -1).tolist()))
        sub_border = {tuple(e) for e in MeshTopology.of(sub).border_halfedges.tolist()}
        assert steps == sub_border
        assert signed_area(surface.vertices, loop) > 0
        assert (topo.find_edges(np.stack([loop, np.roll(loop, -1)], 1)) >= 0).all()
        # control vertices in border order, starting at the one first in the control sequence
        assert p.corners[0] == 0 and np.all(np.diff(p.corners) > 0)
        assert np.array_equal(p.control_vertices, loop[p.corners])
        assert np.array_equal(p.control_indices, [controls.index(c) for c in p.control_vertices.tolist()])
        assert p.control_indices[0] == p.control_indices.min()
        assert set(p.control_vertices.tolist()) == set(controls) & set(p.vertices.tolist())
        assert check_disk(MeshTopology(surface.triangles[p.triangles])).n_border_loops == 1


def test_partition_of_a_grid_into_three_patches() -> None:
    s = source()
    part = partition_surface(s, SOURCE_CONTROLS, SOURCE_FENCES, fence_names=["west", "east", "south"])
    assert part.mesh_name == "source" and len(part.patches) == 3
    check_partition(s, part, SOURCE_CONTROLS)
    by_controls = {tuple(p.control_indices.tolist()): p for p in part.patches}
    assert set(by_controls) == {(0, 1, 8, 7), (1, 2, 3, 8), (3, 4, 5, 6, 7, 8)}
    lower_left = by_controls[(0, 1, 8, 7)]
    assert len(lower_left.triangles) == 2 * 4 * 3
    assert lower_left.border.tolist() == (
        line((0, 0), (4, 0)) + line((4, 1), (4, 3)) + line((3, 3), (0, 3)) + line((0, 2), (0, 1))
    )
    assert lower_left.corners.tolist() == [0, 4, 7, 11]
    top = by_controls[(3, 4, 5, 6, 7, 8)]
    assert top.border[0] == v(8, 3) and top.control_vertices.tolist() == [
        v(8, 3),
        v(8, 6),
        v(4, 6),
        v(0, 6),
        v(0, 3),
        v(4, 3),
    ]
    assert [len(f) for f in part.fence_paths] == [5, 5, 4]


def test_fences_proposed_by_the_shortest_path_helper() -> None:
    s = source()
    others = SOURCE_CONTROLS
    fences = [
        shortest_edge_path(s, a, b, avoid=others)
        for a, b in ((v(0, 3), v(4, 3)), (v(4, 3), v(8, 3)), (v(4, 0), v(4, 3)))
    ]
    part = partition_surface(s, SOURCE_CONTROLS, fences)
    assert len(part.patches) == 3
    check_partition(s, part, SOURCE_CONTROLS)


def test_source_and_target_patches_pair_up() -> None:
    pairing = partition_pair(source(), target(), SOURCE_CONTROLS, TARGET_CONTROLS, SOURCE_FENCES, TARGET_FENCES)
    check_partition(target(), pairing.target, TARGET_CONTROLS)
    assert len(pairing.pairs) == 3
    for pair in pairing.pairs:
        s = pairing.source.patches[pair.source]
        t = pairing.target.patches[pair.target]
        assert np.array_equal(s.control_indices, t.control_indices)
        assert np.array_equal(pair.control_indices, s.control_indices)
        # aligned: the j-th control vertex of one patch pairs with the j-th of the other
        assert [TARGET_CONTROLS.index(c) for c in t.control_vertices.tolist()] == [
            SOURCE_CONTROLS.index(c) for c in s.control_vertices.tolist()
        ]


def test_pairing_survives_renumbering() -> None:
    """The target is the source with vertices renumbered and triangles reordered: patches map onto each other."""
    s = source()
    t, new_of_old = shuffled(s, seed=5)
    t_controls = new_of_old[SOURCE_CONTROLS].tolist()
    t_fences = [new_of_old[f] for f in SOURCE_FENCES]
    pairing = partition_pair(s, t, SOURCE_CONTROLS, t_controls, SOURCE_FENCES, t_fences)
    for pair in pairing.pairs:
        sp, tp = pairing.source.patches[pair.source], pairing.target.patches[pair.target]
        assert np.array_equal(new_of_old[sp.control_vertices], tp.control_vertices)
        assert np.array_equal(new_of_old[sp.border], tp.border)
        assert np.array_equal(np.sort(new_of_old[sp.vertices]), tp.vertices)


def test_pair_patches_directly() -> None:
    a = partition_surface(source(), SOURCE_CONTROLS, SOURCE_FENCES)
    b = partition_surface(target(), TARGET_CONTROLS, TARGET_FENCES, mesh_name="target")
    pairs = pair_patches(a, b)
    assert sorted((p.source, p.target) for p in pairs) == sorted(
        (p.index, q.index)
        for p in a.patches
        for q in b.patches
        if p.control_indices.tolist() == q.control_indices.tolist()
    )


def test_validated_fences_are_returned() -> None:
    fences = validate_fence_paths(source(), SOURCE_FENCES, SOURCE_CONTROLS)
    assert [f.tolist() for f in fences] == SOURCE_FENCES and all(f.dtype == np.int64 for f in fences)
    assert validate_control_vertices(source(), SOURCE_CONTROLS).tolist() == SOURCE_CONTROLS


# ---- what is wrong, and where


@pytest.mark.parametrize(
    ("controls", "fences", "names", "message"),
    [
        (
            SOURCE_CONTROLS,
            [[v(0, 3), v(2, 3)]],
            ["mid"],
            r"^source fence path 0 \('mid'\) is not an edge path: vertices 27 and 29 \(positions 0 and 1\) share no edge$",
        ),
        (
            SOURCE_CONTROLS,
            SOURCE_FENCES[:2] + [line((4, 0), (4, 2))],
            None,
            r"^source fence path 2 ends at vertex 22, which is not a source control vertex$",
        ),
        (
            SOURCE_CONTROLS,
            [line((0, 3), (8, 3))],
            ["across"],
            r"^source fence path 0 \('across'\) passes through control vertex 31 \(position 4\): a fence path joins two "
            r"control vertices with none in between; split it there$",
        ),
        (
            SOURCE_CONTROLS[:8],
            [line((0, 3), (8, 3)), line((4, 0), (4, 6))],
            ["row", "column"],
            r"^source fence path 0 \('row'\) and source fence path 1 \('column'\) meet at vertex 31, which is inside "
            r"source fence path 0 \('row'\) and source fence path 1 \('column'\): fence paths may meet at their end "
            r"vertices only$",
        ),
        (
            SOURCE_CONTROLS + [v(1, 3)],
            [[v(0, 3), v(1, 3)], [v(1, 3), v(0, 3)]],
            ["a", "b"],
            r"^source fence path 0 \('a'\) and source fence path 1 \('b'\) share the edge \(27, 28\): fence paths may meet "
            r"at their end vertices only$",
        ),
        (
            SOURCE_CONTROLS,
            [[v(0, 3), v(0, 3), v(1, 3)]],
            None,
            r"^source fence path 0 passes twice through vertex 27 \(positions 0 and 1\)$",
        ),
        ([0, 8, 62, 0], [], None, r"^source control vertex 0 is given twice \(positions 0 and 3\)$"),
        ([0, 8, 99], [], None, r"^source control vertex 99 \(position 2\): not in the mesh, which has 63 vertices$"),
    ],
)
def test_bad_fences_and_controls_are_named(
    controls: list[int], fences: list[list[int]], names: list[str] | None, message: str
) -> None:
    with pytest.raises(InterpolationSetupError, match=message) as info:
        partition_surface(source(), controls, fences, fence_names=names)
    assert len(info.value.problems) == 1


def test_a_control_vertex_on_no_triangle() -> None:
    s = source()
    loose = Surface(np.vstack([s.vertices, [[50.0, 50.0, 0.0]]]), s.triangles)
    with pytest.raises(InterpolationSetupError, match=r"^target control vertex 63 \(position 3\): on no triangle$"):
        partition_surface(loose, [0, 8, 62, 63], [], mesh_name="target")


def test_a_fence_that_separates_nothing() -> None:
    controls = [v(0, 0), v(4, 0), v(8, 0), v(8, 6), v(0, 6), v(4, 3)]
    with pytest.raises(InterpolationSetupError) as info:
        partition_surface(source(), controls, [line((4, 0), (4, 3))], fence_names=["dangling"])
    problems = info.value.problems
    assert problems[0] == (
        "source fence path 0 ('dangling') separates nothing: both sides of its edge (4, 13) are "
        "in source patch 0 (3 of its edges are so); a fence path must run from border to border "
        "or between other fence paths"
    )
    assert problems[1].startswith(
        "source patch 0 (triangles 0, 1, 2, 3 and 92 more; control vertices "
        "[0, 4, 8, 62, 54, 31]): control vertex 31 inside the patch, not on its border"
    )
    assert str(info.value).startswith("source partition: 2 problems\n- source fence path 0 ('dangling')")


def test_a_patch_that_is_not_a_disk() -> None:
    ring = annulus(6, 6)
    with pytest.raises(InterpolationSetupError) as info:
        partition_surface(ring, [0, 5, 35, 30], [])
    assert info.value.problems == (
        "source patch 0 (triangles 0, 1, 2, 3 and 44 more; control vertices [0, 5, 35, 30]) is not a disk: "
        "2 border loops; Euler characteristic V - E + F = 36 - 84 + 48 = 0, not 1",
    )


def test_a_patch_pinched_at_a_vertex() -> None:
    """Two fences leave border vertex 58 into the interior and meet again at 31: the outer patch is pinched at 58."""
    controls = [v(0, 0), v(8, 0), v(8, 6), v(0, 6), v(4, 6), v(4, 3)]
    fences = [line((4, 6), (4, 3)), [v(4, 3), v(3, 3), v(2, 3), v(2, 4), v(2, 5), v(3, 5), v(4, 6)]]
    with pytest.raises(InterpolationSetupError) as info:
        partition_surface(source(), controls, fences)
    assert info.value.problems[0] == (
        "source patch 0 (triangles 0, 1, 2, 3 and 83 more; control vertices [0, 8, 62, 54, 58, 31]) is not a disk: "
        "1 non-manifold vertex (whose triangles form separate fans): 58; "
        "Euler characteristic V - E + F = 62 - 149 + 87 = 0, not 1"
    )  # 58 as in the mesh, not the patch's own number
    assert any(
        p.startswith("source patch 1 (")
        and p.endswith("has 2 control vertices: a patch needs at least 3 (the corners of its polygon)")
        for p in info.value.problems
    )


def test_a_patch_with_too_few_control_vertices() -> None:
    with pytest.raises(
        InterpolationSetupError,
        match=r"^source patch 1 \(triangles 4, 5, 6, 7 and 44 more; "
        r"control vertices \[4, 58\]\) has 2 control vertices: a patch needs at least 3 ",
    ):
        # a fence down the middle: the right half has only the fence's ends as control vertices
        partition_surface(source(), [v(0, 0), v(4, 0), v(4, 6), v(0, 6)], [line((4, 0), (4, 6))])


def test_a_control_vertex_inside_its_patch() -> None:
    with pytest.raises(
        InterpolationSetupError,
        match=r"^source patch 0 \(triangles 0, 1, 2, 3 and 92 more; control "
        r"vertices \[0, 8, 62, 54, 31\]\): control vertex 31 inside the patch, not on its border$",
    ):
        partition_surface(source(), [v(0, 0), v(8, 0), v(8, 6), v(0, 6), v(4, 3)], [])


def test_different_numbers_of_patches() -> None:
    with pytest.raises(InterpolationSetupError) as info:
        partition_pair(source(), target(), SOURCE_CONTROLS, TARGET_CONTROLS, SOURCE_FENCES, TARGET_FENCES[:2])
    assert info.value.problems[0].startswith(
        "source has 3 patches and target 2: every patch needs a counterpart "
        "(control vertex pairs of each source patch 0: [0, 1, 8, 7]; "
    )
    assert any(
        p.startswith("source patch") and "has no target patch with the same control vertex pairs" in p
        for p in info.value.problems
    )


def test_patches_with_no_counterpart() -> None:
    target_fences = TARGET_FENCES[:2] + [line((2, 2), (2, 4), 5)]  # the target splits its top half instead
    with pytest.raises(InterpolationSetupError) as info:
        partition_pair(source(), target(), SOURCE_CONTROLS, TARGET_CONTROLS, SOURCE_FENCES, target_fences)
    problems = info.value.problems
    assert (
        "source patch 0 (control vertex pairs [0, 1, 8, 7], source vertices [0, 4, 31, 27]) has no target "
        "patch with the same control vertex pairs" in problems
    )
    assert any(
        p.startswith("target patch") and p.endswith("has no source patch with the same control vertex pairs")
        for p in problems
    )
    assert str(info.value).startswith("patch pairing: ")


def test_patches_in_another_cyclic_order() -> None:
    s = grid(5, 4)
    corners = [0, 4, 19, 15]
    with pytest.raises(
        InterpolationSetupError,
        match=r"^source patch 0 \(control vertex pairs \[0, 1, 2, 3\], "
        r"source vertices \[0, 4, 19, 15\]\) and target patch 0 \(control vertex pairs \[0, 2, 1, 3\], "
        r"target vertices \[0, 4, 19, 15\]\) have the same control vertex pairs in a different cyclic "
        r"order along their borders$",
    ):
        partition_pair(s, s, corners, [0, 19, 4, 15])


def test_a_target_oriented_the_other_way() -> None:
    s = grid(5, 4)
    flipped = Surface(s.vertices, s.triangles[:, ::-1])
    corners = [0, 4, 19, 15]
    with pytest.raises(
        InterpolationSetupError,
        match=r"different cyclic order along their borders \(reversed: are "
        r"the triangles of one mesh oriented the other way\?\)$",
    ):
        partition_pair(s, flipped, corners, corners)


def test_different_numbers_of_control_vertices() -> None:
    with pytest.raises(
        InterpolationSetupError,
        match=r"^source has 8 control vertices and target 7: control vertices "
        r"pair up by position in the two sequences$",
    ):
        partition_pair(source(), target(), SOURCE_CONTROLS[:8], TARGET_CONTROLS[:7], [], [])
    a = partition_surface(source(), SOURCE_CONTROLS, SOURCE_FENCES)
    b = partition_surface(target(), TARGET_CONTROLS + [v(1, 0, 5)], TARGET_FENCES, mesh_name="target")
    with pytest.raises(InterpolationSetupError, match=r"^source has 9 control vertices and target 10"):
        pair_patches(a, b)


def test_both_meshes_are_checked_at_once() -> None:
    with pytest.raises(InterpolationSetupError) as info:
        partition_pair(
            source(),
            target(),
            SOURCE_CONTROLS,
            TARGET_CONTROLS,
            [[v(0, 3), v(2, 3)]] + SOURCE_FENCES[1:],
            TARGET_FENCES[:2] + [[v(2, 0, 5), v(2, 2, 5)]],
            source_fence_names=["w"],
            target_fence_names=[None, None, "s"],
        )
    lines = str(info.value).splitlines()
    assert lines[0] == "interpolation set-up: 2 problems"
    assert lines[1].startswith("- source fence path 0 ('w') is not an edge path: vertices 27 and 29")
    assert lines[2].startswith("- target fence path 2 ('s') is not an edge path: vertices 2 and 12")
