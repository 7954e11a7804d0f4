"""The paper's results reproduced: the §6 experiment on a virtual bench, the fitted preset, Table 2."""
