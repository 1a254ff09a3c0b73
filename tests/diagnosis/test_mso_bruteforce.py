"""An independent enumeration of the minimal structurally overdetermined (MSO) sets, against ``mso_sets``.

Nothing here uses :mod:`diagnosis.structural` beyond the structure it reads (which unknowns each equation
holds, which equations each fault acts on): the matchings are this file's own augmenting paths, and the
sets are found by growing connected sets of equations, not by the library's top-down reduction.

The definition checked: ``S`` is an MSO set iff ``|S| = |X(S)| + 1`` (``X``: the unknowns its equations
hold) and, for every equation ``e`` of ``S``, ``S - e`` has a matching that covers all its equations.
(Then ``S`` has redundancy one and every equation lies in its overdetermined part, so ``S`` is a proper
structurally overdetermined set of redundancy one, which is minimal; conversely a minimal set has both
properties.)

The growth is sound for three reasons.  An MSO set is connected (equations joined by shared unknowns).
Every proper subset of an MSO set is covered by a matching, so a grown set that is not covered is either
the MSO set itself or in none.  Every unknown of an MSO set is held by two of its equations (removing the
only holder would leave ``S - e`` with more equations than unknowns), so while a grown set holds an
unknown only one of its equations holds, every MSO set containing it holds another holder of that unknown:
growing by those holders alone reaches every MSO set.  Each set is grown from its lowest equation.
"""

import itertools
import random
import warnings

import pytest

from bondgraph import library as lib
from diagnosis import ARRWarning, StructuralModel, derive_arrs, structural_model
from diagnosis.elimination import faults_of_arr, unreached
from tests.zoo.chain import cases


def _augment(row, unknowns, owner: dict) -> bool:
    """Match equation ``row`` by an augmenting path (Kuhn); ``owner``: unknown -> equation, updated in place."""
    tried = set()

    def search(r) -> bool:
        for x in unknowns[r]:
            if x in tried:
                continue
            tried.add(x)
            if owner.get(x) is None or search(owner[x]):
                owner[x] = r
                return True
        return False

    return search(row)


def _covered(rows, unknowns) -> bool:
    """Whether a matching covers every equation of ``rows``."""
    owner: dict = {}
    return all(_augment(r, unknowns, owner) for r in rows)


def _is_mso(rows: frozenset, unknowns) -> bool:
    """The definition, directly: one more equation than unknowns, and every one-smaller subset covered."""
    held = frozenset().union(*(unknowns[r] for r in rows))
    return len(rows) == len(held) + 1 and all(_covered(rows - {r}, unknowns) for r in rows)


def brute_force_msos(unknowns) -> set:
    """Every MSO set of the structure ``unknowns`` (a sequence of sets of unknowns, one per equation)."""
    holders: dict = {}
    for i, xs in enumerate(unknowns):
        for x in xs:
            holders.setdefault(x, set()).add(i)
    found = set()
    for first in range(len(unknowns)):
        allowed = set(range(first, len(unknowns)))   # the sets whose lowest equation is ``first``
        owner: dict = {}
        if not _augment(first, unknowns, owner):   # an equation of known variables only
            found.add(frozenset({first}))
            continue
        seen = {frozenset({first})}
        stack = [(frozenset({first}), owner)]
        while stack:
            rows, owner = stack.pop()
            count: dict = {}
            for r in rows:
                for x in unknowns[r]:
                    count[x] = count.get(x, 0) + 1
            dangling = [x for x, c in count.items() if c == 1]
            if dangling:   # an MSO set above ``rows`` holds another holder of each of them: branch on the fewest
                options = min(((holders[x] & allowed) - rows for x in dangling), key=len)
            else:
                options = set().union(*(holders[x] for x in count)) & allowed - rows
            for e in options:
                grown = rows | {e}
                if grown in seen:
                    continue
                seen.add(grown)
                extended = dict(owner)
                if _augment(e, unknowns, extended):
                    stack.append((grown, extended))
                elif _is_mso(grown, unknowns):
                    found.add(grown)
    return found


def brute_force_isolability(faults: dict, sets) -> tuple[set, dict]:
    """Detectable faults (an MSO set holds one of their equations) and fault -> the faults it is isolable from
    (an MSO set holds one of its equations and none of theirs)."""
    detectable = {a for a, rows in faults.items() if any(rows & s for s in sets)}
    isolable = {a: {b for b in faults if b != a and any(faults[a] & s and not faults[b] & s for s in sets)}
                for a in faults}
    return detectable, isolable


def _all_subsets_msos(unknowns) -> set:
    """The definition over every subset: for the random structures of at most 10 equations."""
    rows = range(len(unknowns))
    return {frozenset(s) for k in range(1, len(unknowns) + 1) for s in itertools.combinations(rows, k)
            if _is_mso(frozenset(s), unknowns)}


def _random_structure(seed: int, equations: int, unknowns: int) -> list:
    rng = random.Random(seed)
    names = [f"x{j}" for j in range(unknowns)]
    return [frozenset(rng.sample(names, rng.choice([0, 1, 1, 2, 2, 2, 3]))) for _ in range(equations)]


def test_the_textbook_structure_has_its_three_minimal_sets():
    # e0, e1 hold x0; e2 holds x0 and x1; e3 holds x1; e4 holds x2 only (never redundant)
    unknowns = [{"x0"}, {"x0"}, {"x0", "x1"}, {"x1"}, {"x2"}]
    assert brute_force_msos(unknowns) == {frozenset({0, 1}), frozenset({0, 2, 3}), frozenset({1, 2, 3})}
    assert brute_force_msos([{"x0"}, {"x1"}]) == set()
    assert brute_force_msos([set(), {"x0"}]) == {frozenset({0})}   # a relation of known variables alone


@pytest.mark.parametrize("seed", range(12))
def test_the_grown_sets_are_those_of_every_subset_and_of_mso_sets(seed):
    unknowns = _random_structure(seed, equations=8 + seed % 3, unknowns=5 + seed % 4)
    expected = _all_subsets_msos(unknowns)
    assert brute_force_msos(unknowns) == expected
    model = StructuralModel(tuple(None for _ in unknowns), tuple(unknowns), {})
    assert set(model.mso_sets()) == expected


def _models():
    library = [("dc_motor", lib.dc_motor), ("rlc_circuit", lib.rlc_circuit), ("three_tank", lib.three_tank),
               ("torsion_bar", lib.torsion_bar), ("friction_drive", lib.friction_drive)]
    return library + [(case.name, case.build) for case in cases()]


# the number of MSO sets of each model, counted by this enumeration when it was written (a change of the
# equations a model gives shows here first)
COUNTS = {"dc_motor": 4, "rlc_circuit": 4, "three_tank": 18, "torsion_bar": 6, "friction_drive": 5,
          "heat_exchanger": 26, "rlc_ladder3": 22, "wheatstone_rc": 15, "winch_cart": 11, "duffing_oscillator": 1}


@pytest.mark.parametrize(("name", "build"), _models(), ids=[name for name, _ in _models()])
def test_mso_sets_detectability_and_isolability_equal_the_brute_force(name, build):
    model = structural_model(build())
    sets = brute_force_msos(list(model.unknowns))
    assert sets, f"{name}: no redundancy found"
    if name in COUNTS:
        assert len(sets) == COUNTS[name]
    assert set(model.mso_sets()) == sets
    assert len(model.mso_sets()) == len(sets)   # and no set twice
    detectable, isolable = brute_force_isolability(model.faults, sets)
    assert model.detectable() == detectable
    assert model.isolability() == isolable


#: Models cheap enough to derive in the fast tier; the others run in the slow one.
QUICK = {"dc_motor", "rlc_circuit", "pipe_tank", "rc_ladder2", "level_loop"}


@pytest.mark.parametrize(("name", "build"), [pytest.param(n, b, marks=() if n in QUICK else pytest.mark.slow)
                                             for n, b in _models()], ids=[name for name, _ in _models()])
def test_the_arrs_isolate_every_pair_the_brute_force_sets_do_or_say_why_not(name, build):
    bg = build()
    model = structural_model(bg)
    detectable, isolable = brute_force_isolability(model.faults, brute_force_msos(list(model.unknowns)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ARRWarning)
        arrs = derive_arrs(bg, max_order=None)
    supports = [faults_of_arr(model, arr) for arr in arrs]
    reached = {(a, b) for a in model.faults for b in model.faults
               if a != b and any(a in s and b not in s for s in supports)}
    structural = {(a, b) for a, others in isolable.items() for b in others}
    left = unreached(bg, arrs, explain=True)
    assert reached <= structural   # no ARR claims what the structure does not allow
    assert structural - reached == set(left["isolate"])   # every pair missed is listed...
    assert all(left["reasons"].get(pair) for pair in left["isolate"])   # ...with its reason
    assert detectable == set().union(*supports) & set(model.faults)
