"""Pareto fronts of (time, error) points: the runs no other run beats in both."""


def pareto_front(points):
    """Indices of the non-dominated points, sorted by time.

    A point (t, e) is dominated when another point has t' <= t and e' <= e with at least one strict.
    Ties (identical points) keep the first occurrence only.
    """
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1], i))
    front = []
    best_error = float("inf")
    for i in order:
        if points[i][1] < best_error:
            front.append(i)
            best_error = points[i][1]
    return front
