"""The graph's client side, shared by the `hems` verbs, the benchmarks and the tests: a client
node that enables, commands and watches the graph (:mod:`graph_client`), waiting until a
recorder holds what a run needs (:mod:`recording`), the graph, its recorder and a client
started and stopped together (:mod:`recorded_run`), and the step figures read back from a bag
(:mod:`step_figures`)."""

# A new process on this host matched the graph's endpoints 0.1-3.8 s after it started (idle
# graph; longer on a busy host): the graph's participants learn of it from its first
# announcements, but it learns of them only from their periodic ones. Waits for the graph's
# readers and writers default to this; they end as soon as the match comes.
DISCOVERY_S = 10.0
