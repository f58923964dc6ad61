//! The controller's equations, shared by the continuous simulation and the real-time controller.
