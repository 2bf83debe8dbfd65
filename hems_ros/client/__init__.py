"""The graph's client side, shared by the `hems` verbs, the benchmarks and the tests: a client
node that enables, commands and watches the graph (:mod:`graph_client`), waiting until a
recorder holds what a run needs (:mod:`recording`), and the step figures read back from a bag
(:mod:`step_figures`)."""
