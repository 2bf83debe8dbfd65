"""rclpy helpers shared by the nodes, the client and the benchmarks: QoS profiles, the clock,
serialized messages, the lean node and its spin loop, parameter declaration, the runner that
starts a node process, and the middleware threads' scheduling."""
