"""The shipped examples' scenarios and geometry files, as package data (``liftoff.examples``):
``liftoff init --example single_stick DIR`` copies examples/single_stick's scenario and its
files from here (liftoff.config.extends.EXAMPLES). Nothing here is imported as code."""
