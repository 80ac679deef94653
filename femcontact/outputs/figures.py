"""What every report figure shares: plain tick labels on a short log axis."""


def plain_log_ticks(axes, spec: dict) -> None:
    """Tick labels 2, 3, 4 instead of 2 x 10^0 on a log axis spanning less than two decades
    (`spec`: a [[plot]] table, its `logx` and `logy`)."""
    from matplotlib.ticker import FuncFormatter

    for name, axis, limits in (("logx", axes.xaxis, axes.get_xlim()), ("logy", axes.yaxis, axes.get_ylim())):
        if spec[name] and min(limits) > 0 and max(limits) / min(limits) < 100:
            axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
            axis.set_minor_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
