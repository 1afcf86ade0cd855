"""Plant models: the atmosphere, the vehicle's vertical dynamics and its flight controller."""
