"""Reads the files of one run per line that the results scripts take: "KEY SEED ATE ..." (KEY a
start frame or a sequence name, SEED the run's ransac_order_seed, ATE its ATE RMSE in metres)."""


def read_runs(path, key_type):
    """{(key_type(KEY), int(SEED)): float(ATE)} over the file's non-blank lines."""
    runs = {}
    with open(path) as f:
        for line in f:
            if line.strip():
                key, seed, ate = line.split()[:3]
                runs[(key_type(key), int(seed))] = float(ate)
    return runs
