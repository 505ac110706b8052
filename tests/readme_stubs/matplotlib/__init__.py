"""A stand-in for matplotlib where it is not installed (it is no dependency of linkbook): the
README's plotting example runs against it, and its pyplot records what was plotted."""
