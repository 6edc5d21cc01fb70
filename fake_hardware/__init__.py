"""fake_hardware."""
