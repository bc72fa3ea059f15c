!> Look-ups by label and small checks shared by model_build and its other submodules.
submodule (model_build) model_build_lookup
  implicit none

contains

  module procedure node_index
    do idx = 1, size(scene%nodes)
      if (scene%nodes(idx)%label == label) return
    end do
    idx = 0
  end procedure node_index

  module procedure link_index
    do idx = 1, size(scene%links)
      if (scene%links(idx)%label == label) return
    end do
    idx = 0
  end procedure link_index

  module procedure motion_index
    do idx = 1, size(scene%motions)
      if (scene%motions(idx)%label == label) return
    end do
    idx = 0
  end procedure motion_index

  module procedure require_node
    idx = node_index(scene, label)
    if (idx == 0) call err%set(ERR_INPUT, where // ': variable ''' // var // &
      ''': node ''' // label // ''' is not defined (no &node with that label)')
  end procedure require_node

  !> Rotation coordinate of a node, created on first use.
  module procedure node_rotation
    if (b%node_rot(i) == 0) b%node_rot(i) = model%add_coord(0.0_wp, COORD_PHI, &
      scene%nodes(i)%fix_phi, 'node ''' // scene%nodes(i)%label // ''' phi')
    idx = b%node_rot(i)
  end procedure node_rotation

  module procedure require_positive
    character(len=40) :: buf
    if (value > 0.0_wp) return
    write(buf, '(g0)') value
    call err%set(ERR_INPUT, where // ': variable ''' // var // ''' must be positive, got ' // &
      trim(buf))
  end procedure require_positive

end submodule model_build_lookup
