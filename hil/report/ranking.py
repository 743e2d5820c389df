"""When two controllers' figures differ, and when a CCQ is the bench's noise.

One definition for the comparison scripts (preset_comparison.py,
ccq_calibration.py). Plain Python, no third-party module.

A CCQ (paper 003's cross-coupling quotient: peak time x p-p of the perturbed
axis / the primary motion) is *at the noise* when it is below NOISE_FACTOR
times the CCQ of the same axis at rest over an equally long window (metrics.json
`<prefix>_ccq_rest_noise_<axis>...`, the same quotient of the rest p-p):
there the perturbation is the bench's sensor noise, not coupling, and two
controllers whose CCQs are both at the noise differ only by which noise
samples fell in their windows. (The same rule as ccq_calibration.py's
"above noise": p-p >= 2 x rest p-p.)

Two medians over error seeds differ when the seeds' [min, max] ranges do not
overlap; with overlapping ranges the seed-to-seed spread is as large as the
difference, and neither controller is ranked above the other.
"""

NOISE_FACTOR = 2.0


def is_ccq(key):
    return "_ccq_" in key and "_ccq_rest_noise_" not in key


def rest_noise_key(key):
    """The metrics.json key of a CCQ's rest-noise quotient."""
    return key.replace("_ccq_", "_ccq_rest_noise_", 1)


def above_noise(value, rest):
    """A CCQ (or p-p) value is coupling, not noise: at least NOISE_FACTOR x its rest value."""
    return value is not None and rest is not None and value >= NOISE_FACTOR * rest


def higher_is_better(key):
    return any(s in key for s in ("crossover", "phase_margin", "bandwidth"))


def neutral(key):
    # Closeness to the paper, not better or worse: the closed-loop peak.
    return "peak_dB" in key


def rank(key, a, b, rest_a=None, rest_b=None):
    """Which of two controllers is better on one figure.

    a, b: (median, min, max) over the error seeds (None: no value).
    rest_a, rest_b: median rest-noise CCQs (CCQ keys only).
    Returns 'a', 'b', 'equal', 'tie: noise', 'tie: spread' or '-'.
    """
    if a is None or b is None or a[0] is None or b[0] is None or neutral(key):
        return "-"
    if a[0] == b[0]:
        return "equal"
    if is_ccq(key) and not above_noise(a[0], rest_a) and not above_noise(b[0], rest_b):
        return "tie: noise"
    if a[1] <= b[2] and b[1] <= a[2]:
        return "tie: spread"
    a_better = (a[0] > b[0]) if higher_is_better(key) else (a[0] < b[0])
    return "a" if a_better else "b"
