

def test_p2_takes_the_rule_based_fibres_at_its_quadrature_points():
    # the same rule at the 4 points of each P2 element: orthonormal frames whose mean fibre
    # is the element's; P1 (one point, the barycentre) and replaced frames keep the scene's
    from dataclasses import replace

    import numpy as np

    from reference_fem.point_fibres import quadrature_frames
    from reference_fem.space import Space

    scene = _scene("land-ventricle-active")
    q = quadrature_frames(scene, Space(scene.mesh, 2, 2))
    assert q.shape == (scene.mesh.n_tets, 4, 3, 3)
    assert np.allclose(np.einsum("eqij,eqkj->eqik", q, q), np.eye(3), atol=1e-12)
    mean = q[:, :, 0].mean(axis=1)
    mean /= np.linalg.norm(mean, axis=1, keepdims=True)
    assert np.median(np.abs((mean * scene.frames[:, 0]).sum(axis=1))) > 0.99
    assert np.abs(q[:, :, 0] - q[:, :1, 0]).max() > 0.1  # the fibre turns inside elements
    assert quadrature_frames(scene, Space(scene.mesh, 1, 1)) is None
    turned = replace(scene, frames=scene.frames[:, [1, 0, 2]])
    assert quadrature_frames(turned, Space(scene.mesh, 2, 2)) is None
