def json(result):
    return {}
def section(result):
    return None
