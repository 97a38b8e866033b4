"""dse.explore.pareto against the definition, point by point (directed cases and random ones)."""
import itertools

from hypothesis import given, settings, strategies as hs

from dse.explore import pareto


def brute_front(values, dirs):
    def better_eq(a, b):
        return all((x >= y) if d == "max" else (x <= y) for x, y, d in zip(a, b, dirs))

    return [i for i, v in enumerate(values)
            if not any(better_eq(w, v) and w != v for j, w in enumerate(values) if j != i)]


def test_directed():
    dirs = ["max", "min"]  # rays/s up, LUTs down
    v = [(10, 5), (10, 5), (8, 1), (12, 9), (9, 6), (12, 10), (1, 1)]
    # duplicates both stay; (9,6) is dominated by (10,5); (12,10) by (12,9); (1,1) by (8,1)
    assert pareto.front(v, dirs) == [0, 1, 2, 3]
    assert pareto.front([], dirs) == []
    assert pareto.front([(3, 3)], dirs) == [0]
    assert pareto.front([(1,), (3,), (3,), (2,)], ["max"]) == [1, 2]
    assert pareto.ranks(v, dirs) == [0, 0, 0, 0, 1, 1, 1]


@settings(max_examples=200, deadline=None)
@given(hs.integers(1, 3).flatmap(lambda k: hs.tuples(
    hs.lists(hs.tuples(*[hs.integers(0, 6)] * k), max_size=30), hs.lists(hs.sampled_from(["max", "min"]), min_size=k, max_size=k))))
def test_random_against_brute_force(case):
    values, dirs = case
    assert pareto.front(values, dirs) == brute_front(values, dirs)
    r = pareto.ranks(values, dirs)
    # every point of rank k+1 is dominated by a point of rank k, and none of rank k dominates another of rank k
    for k in set(r):
        same = [values[i] for i in range(len(values)) if r[i] == k]
        assert len(brute_front(same, dirs)) == len(same)
        if k:
            prev = [values[i] for i in range(len(values)) if r[i] == k - 1]
            for v in same:
                assert len(brute_front(prev + [v], dirs)) <= len(prev)  # v is not on the front of prev + v
    assert all(a == b for a, b in itertools.zip_longest(sorted(set(r)), range(len(set(r)))))
