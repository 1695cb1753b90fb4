# Two models in StructuralIdentifiability.jl's benchmarks.jl layout (written for this seed).
benchmarks = Dict(
    :A => Dict(
        :name => "A",
        :cite => "\\cite{a}",
        :ode => @ODEmodel(
            x1'(t) = -(a + b) * x1(t) // c + u(t),
            x2'(t) = x1(t)^2 - k * x2(t) + q,
            y(t) = x2(t)
        ),
    ),
    :L => Dict(:ode => linear_compartment_model([[2], [1]], inputs = [1], outputs = [2], leaks = [2])),
)
ode = @ODEmodel(z'(t) = -k * z(t) + c * exp(w(t)), w'(t) = 0, y(t) = z(t))
ode = set_parameter_values(ode, Dict(c => QQ(1, 2)))
benchmarks[:B] = Dict(:name => "B", :ode => ode)
