"""What runs around the method: threads, interrupts, memory, optional extras."""
