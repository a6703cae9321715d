"""What every layer of omnikin shares: input checks, message text, numbers as text, random
generators and the memory/time budget of a job.

- :mod:`~omnikin.common.arrays`: real numbers, shapes, ranges and finiteness of inputs, with
  one-line refusals.
- :mod:`~omnikin.common.messages`: how a message quotes a value
  (:func:`~omnikin.common.messages.shorten`), suggests a name
  (:func:`~omnikin.common.messages.did_you_mean`) and writes numbers that differ
  (:func:`~omnikin.common.messages.digits_apart`).
- :mod:`~omnikin.common.number_text`: the one grammar of numbers read from text, and numbers
  written for people (millimetres, ratios, reduction factors).
- :mod:`~omnikin.common.rng`: random generators from seeds (no global state).
- :mod:`~omnikin.common.resource_limits`: a job's estimated memory and time against its limits.

Nothing here knows a robot; everything above imports it.
"""
