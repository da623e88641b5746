"""matplotlib for files, not screens: the Agg backend, imported only when a plot is drawn
(matplotlib costs ~0.5 s to import; most pydem commands never plot)."""


def pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt
