!> Spatial (&scene dimension = 3) and planar scenes take different variables and groups; a
!> variable of the other kind is an error, never silently dropped. Checked once every group is
!> read, since &scene may come last in the file.
submodule (io_scene) io_scene_dimension
  implicit none

contains

  module subroutine check_dimension(scene, err)
    type(scene_t), intent(in) :: scene
    type(error_t), intent(inout) :: err
    integer :: i
    do i = 1, size(scene%nodes)
      associate (n => scene%nodes(i))
        if (err%ok() .and. scene%dimension == 3 .and. len(n%planar_var) > 0) call err%set( &
          ERR_INPUT, 'group &node ''' // n%label // ''': variable ''' // n%planar_var // &
          ''' is planar only: a spatial node''s rotation is an input through dynamic = ' // &
          '''rotation'' or motion_rotation (fix_rotation clamps it)')
        call mismatch('node', n%label, n%spatial_var, n%planar_var, scene%dimension, err)
      end associate
    end do
    do i = 1, size(scene%links)
      associate (r => scene%links(i))
        call mismatch('link', r%label, r%spatial_var, '', scene%dimension, err)
        if (err%ok() .and. scene%dimension == 3) then
          if (.not. r%torsion > 0) call err%set(ERR_INPUT, 'group &link ''' // r%label // &
            ''': variable ''J'' (the torsion constant, > 0) is required in a spatial scene')
          if (err%ok() .and. .not. r%shear_modulus > 0) call err%set(ERR_INPUT, 'group &link ''' &
            // r%label // ''': variable ''G'' (> 0) is required in a spatial scene (torsion ' // &
            'stiffness G J; it also makes the bending shear-flexible)')
        end if
      end associate
    end do
    do i = 1, size(scene%sliders)
      if (.not. err%ok()) exit
      if (size(scene%sliders(i)%direction) /= scene%dimension) call err%set(ERR_INPUT, &
        'group &slider ''' // scene%sliders(i)%label // ''': variable ''direction'' needs ' // &
        trim(merge('2 values (dx, dy) in a planar scene     ', &
        '3 values (dx, dy, dz) in a spatial scene', scene%dimension == 2)))
    end do
    do i = 1, size(scene%hinges)
      call mismatch('hinge', scene%hinges(i)%label, scene%hinges(i)%spatial_var, '', &
        scene%dimension, err)
    end do
    do i = 1, size(scene%masses)
      call mismatch('mass', 'on node ''' // scene%masses(i)%node // '''', &
        scene%masses(i)%spatial_var, scene%masses(i)%planar_var, scene%dimension, err)
    end do
    do i = 1, size(scene%forces)
      call mismatch('force', 'on node ''' // scene%forces(i)%node // '''', &
        scene%forces(i)%spatial_var, scene%forces(i)%planar_var, scene%dimension, err)
    end do
  end subroutine check_dimension

  subroutine mismatch(group, label, spatial_var, planar_var, dimension, err)
    character(len=*), intent(in) :: group, label, spatial_var, planar_var
    integer, intent(in) :: dimension
    type(error_t), intent(inout) :: err
    character(len=:), allocatable :: who
    if (.not. err%ok()) return
    who = 'group &' // group // ' '
    if (label(1:min(3, len(label))) /= 'on ') who = who // ''''
    who = who // label
    if (label(1:min(3, len(label))) /= 'on ') who = who // ''''
    if (dimension == 2 .and. len(spatial_var) > 0) call err%set(ERR_INPUT, who // &
      ': variable ''' // spatial_var // ''' needs a spatial scene (&scene dimension = 3)')
    if (dimension == 3 .and. len(planar_var) > 0) call err%set(ERR_INPUT, who // &
      ': variable ''' // planar_var // ''' is planar only' // spatial_counterpart(planar_var))
  end subroutine mismatch

  !> What a spatial scene takes instead of a planar-only variable.
  function spatial_counterpart(planar_var) result(hint)
    character(len=*), intent(in) :: planar_var
    character(len=:), allocatable :: hint
    select case (planar_var)
    case ('J')
      hint = ': in a spatial scene a body''s rotary inertia is the tensor ''inertia'''
    case ('moment')
      hint = ': in a spatial scene a moment is ''mx'', ''my'', ''mz'' (global axes)'
    case default
      hint = ''
    end select
  end function spatial_counterpart
end submodule io_scene_dimension
