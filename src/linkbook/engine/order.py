"""The order of evaluation: groups in topological order of their strongly connected components
(a group that reads itself, or a cycle of groups, is evaluated cell by cell in cell order), after
splitting the groups that tie several groups into one cycle.  `owner` and `member` are, per
sheet, grids like the value grid holding the group (gid) and member index of each formula cell
(-1 elsewhere)."""
from __future__ import annotations

import numpy as np

from .errors import CircularReferenceError
from .groups import Group
from .references import cell_name


def group_deps(g: Group, owner: dict[str, np.ndarray]) -> set[int]:
    """The groups owning a cell that g reads (by `owner`, one grid per sheet)."""
    deps = found_in(g, owner)
    deps.discard(-1)
    return deps


def found_in(g: Group, grids: dict[str, np.ndarray]) -> set[int]:
    """The values of `grids` (one per sheet, shaped like the value grid) over every cell
    that group g reads."""
    found = set()
    if g.mode == "each":
        for i in range(len(g.members)):
            for sheet, r1, c1, r2, c2 in g.reads(i):
                found.update(grids[sheet][r1:r2 + 1, c1:c2 + 1].ravel().tolist())
    else:
        for d in g.inputs:
            grid = grids[d.sheet]
            if not d.is_range:
                r1, c1, _, _ = d.at(g.rows, g.cols)
                found.update(grid[r1, c1].ravel().tolist())
                continue
            hosts = [(g.rows[0], g.cols[0])] if d.is_absolute else zip(g.rows, g.cols)
            for row, col in hosts:
                _, r1, c1, r2, c2 = d.rect(int(row), int(col))
                found.update(grid[r1:r2 + 1, c1:c2 + 1].ravel().tolist())
    return found


def components_of(groups: list[Group], owner) -> tuple[list[list[int]], set[int]]:
    """Strongly connected components of the group graph, dependencies first (Tarjan), and
    the groups that read themselves."""
    deps = [sorted(group_deps(g, owner)) for g in groups]
    self_reading = {g.gid for g in groups if g.gid in deps[g.gid]}
    index, low, on_stack, stack, out, counter = {}, {}, set(), [], [], [0]
    for root in range(len(groups)):
        if root in index:
            continue
        work = [(root, 0)]
        while work:
            v, i = work.pop()
            if i == 0:
                index[v] = low[v] = counter[0]
                counter[0] += 1
                stack.append(v)
                on_stack.add(v)
            if i < len(deps[v]):
                work.append((v, i + 1))
                w = deps[v][i]
                if w not in index:
                    work.append((w, 0))
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
                continue
            if low[v] == index[v]:
                component = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    component.append(w)
                    if w == v:
                        break
                out.append(component)
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[v])
    return out, self_reading


def untangled_components(groups: list[Group], owner, member, stats: dict,
                         keep=lambda component: False) -> tuple[list[list[int]], set[int]]:
    """components_of() after splitting the groups that tie several groups into one cycle.

    A group joins cells by shape, not by position, so two groups can read each other
    without any cell reading itself: `=SQRT(E5^2+F5^2)` in columns G and M of a sweep is one
    group, and if M reads a column that reads G, the two groups are one cycle.  Evaluated
    cell by cell, such a cycle costs a compiled call per cell.  So a group of a cycle that
    spans several columns is split into one group per column; where no such group is left,
    the smallest groups are split into single cells; and again, until every cycle left is
    real (a column that reads itself, or a circular reference).  A sweep column stays
    whole, and so does a cycle of one-column groups that `keep` takes (a row recurrence,
    evaluated as a scan: scan.py)."""
    while True:
        components, self_reading = components_of(groups, owner)
        victims = []
        for component in components:
            if len(component) < 2:
                continue
            parts = [groups[gid] for gid in component]
            wide = [g for g in parts if len(set(g.cols.tolist())) > 1]
            if wide:
                victims += [(g, lambda m: m.col) for g in wide]
                continue
            if keep(component):
                continue
            splittable = [len(g.members) for g in parts if len(g.members) > 1]
            victims += [(g, lambda m: (m.row, m.col)) for g in parts
                        if splittable and len(g.members) == min(splittable)]
        if not victims:
            return components, self_reading
        for g, key in victims:
            split(g, key, groups, owner, member)
        stats["split_groups"] += len(victims)


def split(g: Group, key, groups: list[Group], owner, member) -> None:
    """One group per value of key(member); the first keeps the gid, all share the compiled
    function and its inputs."""
    parts: dict[object, list[int]] = {}
    for i, m in enumerate(g.members):
        parts.setdefault(key(m), []).append(i)
    index = list(parts.values())
    for idx in index[1:]:
        part = Group(len(groups), g.sheet, g.shape, g.members.take(idx),
                     g.info, g.descs, g.mode, g.func, g.inputs, g.batch,
                     [g.each[i] for i in idx] if g.each else [])
        groups.append(part)
        owner[g.sheet][part.rows, part.cols] = part.gid
        member[g.sheet][part.rows, part.cols] = np.arange(len(idx))
    first = index[0]
    g.members = g.members.take(first)
    g.each = [g.each[i] for i in first] if g.each else []


def cell_order(groups: list[Group], gids: set[int], owner, member,
               stats: dict) -> list[tuple[int, int]]:
    """Members of mutually dependent groups in dependency order (iterative DFS)."""
    def deps(gid, i):
        found = []
        for sheet, r1, c1, r2, c2 in groups[gid].reads(i):
            owners = owner[sheet][r1:r2 + 1, c1:c2 + 1]
            members = member[sheet][r1:r2 + 1, c1:c2 + 1]
            mask = np.isin(owners, list(gids))
            found += zip(owners[mask].tolist(), members[mask].tolist())
        return found

    order, state = [], {}
    for gid in sorted(gids):
        for i in range(len(groups[gid].members)):
            if (gid, i) in state:
                continue
            state[(gid, i)] = 1
            work = [((gid, i), iter(deps(gid, i)))]
            while work:
                node, it = work[-1]
                for nxt in it:
                    s = state.get(nxt)
                    if s == 1:
                        g = groups[nxt[0]]
                        m = g.members[nxt[1]]
                        raise CircularReferenceError(
                            f"circular reference through {g.sheet}!{cell_name(m.row, m.col)}")
                    if s is None:
                        state[nxt] = 1
                        work.append((nxt, iter(deps(*nxt))))
                        break
                else:
                    work.pop()
                    state[node] = 2
                    order.append(node)
    stats["cyclic_cells"] += len(order)
    return order


def closure(start: set[int], edges: dict[int, set[int]], within: set[int] | None = None
            ) -> set[int]:
    """Every node reached from `start` along `edges` (start included); with `within`, only
    through nodes of it (the others neither reached nor passed through)."""
    reached, todo = set(start), list(start)
    while todo:
        for nxt in edges.get(todo.pop(), ()):
            if nxt not in reached and (within is None or nxt in within):
                reached.add(nxt)
                todo.append(nxt)
    return reached


def downstream(groups: list[Group], grid: dict[str, np.ndarray], places, deps: dict[int, set[int]]
               ) -> set[int]:
    """The groups that read a cell of `places` ((sheet, row, col) each), directly or through
    other groups (`deps`: the groups each group reads; `grid`: a value grid per sheet, for its
    shape)."""
    marks = {s: np.zeros(g.shape, dtype=np.int8) for s, g in grid.items()}
    for sheet, row, col in places:
        marks[sheet][row, col] = 1
    return closure({g.gid for g in groups if 1 in found_in(g, marks)}, _readers(deps))


CHANGED = -2        # a changed place in a copy of the owner grids (no group has this id)


def deps_and_downstream(groups: list[Group], owner: dict[str, np.ndarray], places
                        ) -> tuple[dict[int, set[int]], set[int]]:
    """{gid: group_deps(g, owner)} and downstream() of `places` ((sheet, row, col) of constant
    cells: no group owns them), found in one look at what each group reads: the places
    marked CHANGED in a copy of the owner grids of their sheets."""
    marked = dict(owner)
    for sheet in {sheet for sheet, _, _ in places}:
        marked[sheet] = owner[sheet].copy()
    for sheet, row, col in places:
        if marked[sheet][row, col] >= 0:
            raise ValueError(f"{sheet} row {row} column {col} holds a formula, not a constant")
        marked[sheet][row, col] = CHANGED
    deps, first = {}, set()
    for g in groups:
        found = found_in(g, marked)
        if CHANGED in found:
            first.add(g.gid)
        deps[g.gid] = found - {-1, CHANGED}
    return deps, closure(first, _readers(deps))


def _readers(deps: dict[int, set[int]]) -> dict[int, set[int]]:
    """The groups that read each group (`deps` turned round)."""
    readers: dict[int, set[int]] = {}
    for gid, ds in deps.items():
        for d in ds:
            readers.setdefault(d, set()).add(gid)
    return readers
