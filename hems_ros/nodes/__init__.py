"""ROS 2 node shells: they wire parameters, topics and timers to the plain-Python cores."""
