def section(result):
    return None
