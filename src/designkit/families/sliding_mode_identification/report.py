FIGURES = ()
def section(result):
    return None
def json(result):
    s = result.simulation.signals
    return {"a_hat": float(s["a_hat"][-1]), "b_hat": float(s["b_hat"][-1])}
