"""What runs around the method: threads, the kernels' warm-up, interrupts, optional extras."""
