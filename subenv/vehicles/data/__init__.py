"""The vehicle files shipped with the package, one TOML file a vehicle (:mod:`subenv.vehicles.loader`)."""
