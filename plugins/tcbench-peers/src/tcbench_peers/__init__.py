"""The strongest known optimisers as tcbench plugins (entry-point group ``tcbench.optimisers``).

Each is a thin adapter that turns a peer library's own optimiser into tcbench's ask/tell
protocol (:class:`tcbench.optimisers.protocol.Optimiser`): same bounds, budget accounting and
treatment of NaN/inf as the built-ins, no copy of any algorithm. A peer never evaluates more
than its budget: the last batch is shortened to what remains and the run ends there.
"""
