"""The PWM duty's range, in percent of a period: what a controller may command, what an
actuation unit accepts and what the drive board can apply."""

DUTY_MIN = 0.0
DUTY_MAX = 100.0


def valid_duty(duty_percent: float) -> bool:
    """A finite duty within the range (NaN compares false)."""
    return DUTY_MIN <= duty_percent <= DUTY_MAX
