"""thermogel dose planner: actuation times, schedules, units, validation cache."""
