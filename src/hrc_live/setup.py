from setuptools import find_packages, setup

package_name = 'hrc_live'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['web/*']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/params', ['../../params/display.yaml',
                                               '../../params/foxglove.yaml']),
        ('share/' + package_name + '/params/foxglove', ['../../params/foxglove/hrc_layout.json']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='hrc developers',
    maintainer_email='hrc@example.org',
    description='Live sessions with a person: display page, joystick set-up helper, operator '
                'controls.',
    license='Apache-2.0',
    entry_points={'console_scripts': [
        'display_node = hrc_live.display_node:main',
        'foxglove_node = hrc_live.foxglove_node:main',
    ]},
)
