"""bittc_core: the Binary-TTC network, its data, training, evaluation and the `bittc` CLI."""
